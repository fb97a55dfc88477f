#pragma once
// The browser side of the hub, implemented by the web server (kept C++17: the web server's
// translation unit is compiled as C++17, see CMakeLists.txt).

#include <cstddef>
#include <cstdint>
#include <string>

namespace concert::gui {

using ClientId = uint64_t;

class ClientSink {
 public:
  virtual ~ClientSink() = default;
  /// Queues `message` for `client` (a text or binary WebSocket message). Must not block.
  virtual void send(ClientId client, std::string message, bool binary) = 0;
  /// Bytes queued on the client's socket, not yet sent.
  virtual size_t buffered_bytes(ClientId client) = 0;
};

}  // namespace concert::gui
