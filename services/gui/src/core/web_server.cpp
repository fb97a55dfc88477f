// websocketpp (Debian's libwebsocketpp-dev, header-only) on standalone Asio (libasio-dev): one
// library gives both the HTTP file server and the WebSocket API on one port, on one thread.
// cpp-httplib (also in Debian) was the other candidate; its Debian 12 version (0.11) has no
// WebSocket, and pushing 1 kHz-fed streams through HTTP polling or server-sent events would
// need a second channel for commands and base64 for camera frames.
// Built as C++17 (see web_server.hpp). The same server runs plain (loopback) or over TLS
// (websocketpp's asio_tls config, OpenSSL): one template, two instantiations.
#define ASIO_STANDALONE
#include "gui/web_server.hpp"

#include <atomic>
#include <fstream>
#include <map>
#include <mutex>
#include <sstream>
#include <stdexcept>
#include <thread>
#include <type_traits>

#include <openssl/ssl.h>

#include <websocketpp/config/asio.hpp>
#include <websocketpp/server.hpp>

namespace concert::gui {

namespace {

/// What WebServer needs of a server, whatever its transport.
class Backend {
 public:
  virtual ~Backend() = default;
  virtual uint16_t port() = 0;
  virtual void every(int period_ms, std::function<void()> fn) = 0;
  virtual void start() = 0;
  virtual void stop() = 0;
  virtual void send(ClientId client, std::string message, bool binary) = 0;
  virtual size_t buffered_bytes(ClientId client) = 0;
};

/// The TLS context every connection shares, made once so a bad certificate or key stops the
/// gateway at start, naming the file.
std::shared_ptr<asio::ssl::context> tls_context(const WebServerOptions& o) {
  auto ctx = std::make_shared<asio::ssl::context>(asio::ssl::context::tls_server);
  ctx->set_options(asio::ssl::context::default_workarounds | asio::ssl::context::no_sslv2 |
                   asio::ssl::context::no_sslv3 | asio::ssl::context::no_tlsv1 | asio::ssl::context::no_tlsv1_1 |
                   asio::ssl::context::single_dh_use);
  SSL_CTX_set_min_proto_version(ctx->native_handle(), TLS1_2_VERSION);
  std::error_code ec;
  ctx->use_certificate_chain_file(o.tls_certificate, ec);
  if (ec) throw std::runtime_error("--tls-cert " + o.tls_certificate + ": not a usable PEM certificate (" + ec.message() + ")");
  ctx->use_private_key_file(o.tls_key, asio::ssl::context::pem, ec);
  if (ec) throw std::runtime_error("--tls-key " + o.tls_key + ": not a usable PEM private key (" + ec.message() + ")");
  if (SSL_CTX_check_private_key(ctx->native_handle()) != 1) {
    throw std::runtime_error("--tls-key " + o.tls_key + " is not the key of --tls-cert " + o.tls_certificate);
  }
  return ctx;
}

template <class Config>
class ServerOf final : public Backend {
 public:
  using Server = websocketpp::server<Config>;

  ServerOf(WebServerOptions o, WebServerHandlers h, std::ostream& l, std::shared_ptr<asio::ssl::context> tls)
      : options(std::move(o)), handlers(std::move(h)), log(l), tls_(std::move(tls)) {
    server.clear_access_channels(websocketpp::log::alevel::all);
    server.clear_error_channels(websocketpp::log::elevel::all);
    server.set_error_channels(websocketpp::log::elevel::fatal);
    server.init_asio(&io);
    server.set_reuse_addr(true);
    server.set_max_message_size(options.max_message_bytes);
    if constexpr (std::is_same_v<Config, websocketpp::config::asio_tls>) {
      server.set_tls_init_handler([this](websocketpp::connection_hdl) { return tls_; });
    }
    server.set_http_handler([this](websocketpp::connection_hdl hdl) { serve_http(hdl); });
    server.set_validate_handler(
        [this](websocketpp::connection_hdl hdl) { return server.get_con_from_hdl(hdl)->get_resource() == "/ws"; });
    server.set_open_handler([this](websocketpp::connection_hdl hdl) {
      auto con = server.get_con_from_hdl(hdl);
      const std::string origin = con->get_remote_endpoint();
      auto client = std::make_shared<Client>();
      client->hdl = hdl;
      ClientId id = 0;
      {
        std::lock_guard<std::mutex> lock(mutex);
        id = next_id++;
        clients[id] = client;
        by_hdl[hdl] = id;
      }
      handlers.open(id, origin);
    });
    auto closed = [this](websocketpp::connection_hdl hdl) {
      ClientId id = 0;
      {
        std::lock_guard<std::mutex> lock(mutex);
        auto it = by_hdl.find(hdl);
        if (it == by_hdl.end()) return;
        id = it->second;
        by_hdl.erase(it);
        clients.erase(id);
      }
      handlers.close(id);
    };
    server.set_close_handler(closed);
    server.set_fail_handler(closed);
    server.set_message_handler([this](websocketpp::connection_hdl hdl, typename Server::message_ptr msg) {
      ClientId id = 0;
      {
        std::lock_guard<std::mutex> lock(mutex);
        auto it = by_hdl.find(hdl);
        if (it == by_hdl.end()) return;
        id = it->second;
      }
      if (msg->get_opcode() == websocketpp::frame::opcode::text) handlers.message(id, msg->get_payload());
    });

    std::error_code ec;
    const auto address = asio::ip::make_address(options.bind, ec);
    if (ec) throw std::runtime_error("--bind " + options.bind + ": not an IP address (" + ec.message() + ")");
    server.listen(asio::ip::tcp::endpoint(address, options.port), ec);
    if (ec) {
      throw std::runtime_error("cannot listen on " + options.bind + ":" + std::to_string(options.port) + ": " +
                               ec.message());
    }
    server.start_accept(ec);
    if (ec) throw std::runtime_error("cannot accept on " + options.bind + ": " + ec.message());
  }

  ~ServerOf() override { stop(); }

  uint16_t port() override {
    std::error_code ec;
    const auto endpoint = server.get_local_endpoint(ec);
    return ec ? 0 : endpoint.port();
  }

  void every(int period_ms, std::function<void()> fn) override {
    timers.push_back(std::make_unique<asio::steady_timer>(io));
    repeat(*timers.back(), period_ms, std::move(fn));
  }

  void start() override {
    thread = std::thread([this] { server.run(); });
  }

  void stop() override {
    if (!thread.joinable()) return;
    asio::post(io, [this] {
      stopped = true;
      std::error_code ec;
      server.stop_listening(ec);
      for (auto& t : timers) t->cancel();
      std::lock_guard<std::mutex> lock(mutex);
      for (auto& [id, c] : clients) {
        server.close(c->hdl, websocketpp::close::status::going_away, "gateway stopping", ec);
      }
    });
    // Closing handshakes get a moment; then the loop stops whatever is left.
    std::this_thread::sleep_for(std::chrono::milliseconds(100));
    server.stop();
    thread.join();
  }

  void send(ClientId client, std::string message, bool binary) override {
    std::shared_ptr<Client> c;
    {
      std::lock_guard<std::mutex> lock(mutex);
      auto it = clients.find(client);
      if (it == clients.end()) return;
      c = it->second;
    }
    const size_t size = message.size();
    c->pending += size;
    asio::post(io, [this, c, size, text = std::move(message), binary] {
      std::error_code ec;
      server.send(c->hdl, text, binary ? websocketpp::frame::opcode::binary : websocketpp::frame::opcode::text, ec);
      auto con = server.get_con_from_hdl(c->hdl, ec);
      if (!ec) c->buffered = con->get_buffered_amount();
      c->pending -= size;
    });
  }

  size_t buffered_bytes(ClientId client) override {
    std::lock_guard<std::mutex> lock(mutex);
    auto it = clients.find(client);
    return it == clients.end() ? 0 : it->second->pending + it->second->buffered;
  }

 private:
  struct Client {
    websocketpp::connection_hdl hdl;
    std::atomic<size_t> pending{0};   // posted to the server thread, not yet handed to the socket
    std::atomic<size_t> buffered{0};  // queued on the socket (last seen)
  };

  void serve_http(websocketpp::connection_hdl hdl) {
    auto con = server.get_con_from_hdl(hdl);
    const std::string target = con->get_resource();
    const auto method = con->get_request().get_method();
    const auto file = (method == "GET" || method == "HEAD") ? resolve_request(options.roots, target) : std::nullopt;
    // The app is never framed by another site, and its types are what they say.
    con->append_header("X-Content-Type-Options", "nosniff");
    con->append_header("X-Frame-Options", "DENY");
    if (tls_) con->append_header("Strict-Transport-Security", "max-age=31536000");
    if (!file) {
      con->set_status(websocketpp::http::status_code::not_found);
      con->append_header("Content-Type", "text/plain; charset=utf-8");
      con->set_body("not found: " + target + "\n");
      return;
    }
    std::ifstream in(*file, std::ios::binary);
    std::ostringstream body;
    body << in.rdbuf();
    con->set_status(websocketpp::http::status_code::ok);
    con->append_header("Content-Type", mime_type(*file));
    con->append_header("Cache-Control", "no-cache");
    con->set_body(body.str());
  }

  void repeat(asio::steady_timer& timer, int period_ms, std::function<void()> fn) {
    timer.expires_after(std::chrono::milliseconds(period_ms));
    timer.async_wait([this, &timer, period_ms, fn](const std::error_code& ec) {
      if (ec) return;
      fn();
      // Socket backlogs as seen from the server's thread (ClientSink::buffered_bytes).
      std::lock_guard<std::mutex> lock(mutex);
      for (auto& [id, c] : clients) {
        std::error_code e;
        auto con = server.get_con_from_hdl(c->hdl, e);
        if (!e) c->buffered = con->get_buffered_amount();
      }
      if (!stopped) repeat(timer, period_ms, fn);
    });
  }

  WebServerOptions options;
  WebServerHandlers handlers;
  std::ostream& log;
  std::shared_ptr<asio::ssl::context> tls_;
  asio::io_context io;
  Server server;
  std::thread thread;
  std::mutex mutex;  // clients, by_hdl
  std::map<ClientId, std::shared_ptr<Client>> clients;
  std::map<websocketpp::connection_hdl, ClientId, std::owner_less<websocketpp::connection_hdl>> by_hdl;
  std::vector<std::unique_ptr<asio::steady_timer>> timers;
  bool stopped = false;
  ClientId next_id = 1;
};

}  // namespace

struct WebServer::Impl {
  std::unique_ptr<Backend> backend;
  bool tls = false;
};

WebServer::WebServer(WebServerOptions options, WebServerHandlers handlers, std::ostream& log)
    : impl_(std::make_unique<Impl>()) {
  if (options.tls_certificate.empty() != options.tls_key.empty()) {
    throw std::runtime_error("TLS needs both a certificate and its key");
  }
  if (options.tls_certificate.empty()) {
    impl_->backend = std::make_unique<ServerOf<websocketpp::config::asio>>(std::move(options), std::move(handlers), log,
                                                                          nullptr);
  } else {
    auto ctx = tls_context(options);
    impl_->backend = std::make_unique<ServerOf<websocketpp::config::asio_tls>>(std::move(options), std::move(handlers),
                                                                              log, std::move(ctx));
    impl_->tls = true;
  }
}

WebServer::~WebServer() { stop(); }

uint16_t WebServer::port() const { return impl_->backend->port(); }
bool WebServer::tls() const { return impl_->tls; }
void WebServer::every(int period_ms, std::function<void()> fn) { impl_->backend->every(period_ms, std::move(fn)); }
void WebServer::start() { impl_->backend->start(); }
void WebServer::stop() { impl_->backend->stop(); }
void WebServer::send(ClientId client, std::string message, bool binary) {
  impl_->backend->send(client, std::move(message), binary);
}
size_t WebServer::buffered_bytes(ClientId client) { return impl_->backend->buffered_bytes(client); }

}  // namespace concert::gui
