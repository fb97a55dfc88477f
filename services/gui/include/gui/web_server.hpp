#pragma once
// The gateway's HTTP + WebSocket server (websocketpp on standalone Asio, one thread): GET serves
// the app and the module database's meshes, /ws is the API. C++17 on purpose: websocketpp 0.8.2
// (Debian 12) does not compile as C++20, so its one translation unit is built as C++17 and this
// header stays C++17.

#include <cstdint>
#include <functional>
#include <memory>
#include <ostream>
#include <string>

#include "gui/client_sink.hpp"
#include "gui/static_files.hpp"

namespace concert::gui {

struct WebServerOptions {
  std::string bind = "127.0.0.1";  ///< address to listen on ("0.0.0.0": every interface)
  uint16_t port = 8080;            ///< 0: any free port (see WebServer::port())
  StaticRoots roots;
  /// HTTPS and WSS with this certificate (PEM, the chain after it) and key; both empty: plain
  /// HTTP. TLS 1.2 or newer only.
  std::string tls_certificate;
  std::string tls_key;
  /// A WebSocket message longer than this [bytes] closes the connection (1009, "message too
  /// big"); the hub refuses shorter ones it will not read with a reason.
  size_t max_message_bytes = 4u << 20;
};

struct WebServerHandlers {
  std::function<void(ClientId, const std::string& origin)> open;  ///< the server numbers clients
  std::function<void(ClientId, const std::string& text)> message;
  std::function<void(ClientId)> close;
};

class WebServer : public ClientSink {
 public:
  /// Listens at once. Throws std::runtime_error naming the address and port when it cannot, or
  /// the file when the certificate or key cannot be used.
  WebServer(WebServerOptions options, WebServerHandlers handlers, std::ostream& log);
  ~WebServer() override;
  WebServer(const WebServer&) = delete;
  WebServer& operator=(const WebServer&) = delete;

  /// The port listened on.
  uint16_t port() const;
  /// Whether it serves HTTPS/WSS.
  bool tls() const;
  /// Runs `every` on the server's thread every `period_ms` (e.g. the rates broadcast).
  void every(int period_ms, std::function<void()> every);
  /// Serves on a thread of its own until stop() or destruction.
  void start();
  void stop();

  void send(ClientId client, std::string message, bool binary) override;
  size_t buffered_bytes(ClientId client) override;

 private:
  struct Impl;
  std::unique_ptr<Impl> impl_;
};

}  // namespace concert::gui
