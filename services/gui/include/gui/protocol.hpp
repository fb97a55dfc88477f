#pragma once
// The gateway's WebSocket API: JSON text messages both ways, and binary messages for camera
// frames. Every message is an object with "op".
//
// Browser -> gateway:
//   {"op": "subscribe", "topic": T, "max_hz": R?, "id": N?}   samples of T (R: at most R a second,
//                                                              streams only; capped by the gateway)
//   {"op": "unsubscribe", "topic": T, "id": N?}
//   {"op": "publish", "topic": T, "data": {...}, "id": N?}    an operator command (allow-list)
//   {"op": "ping", "id": N?}
// Gateway -> browser:
//   {"op": "hello", "topics": [...], "commands": [...], "limits": {...}, "client": ORIGIN}
//   {"op": "sample", "topic": T, "instance": K, "data": {...}}  (fields of the IDL type)
//   {"op": "rates", "topics": [{"topic", "hz", "count", "age_s"}...]}   every second
//   {"op": "ack", "id": N, "topic": T}    |   {"op": "error", "id": N?, "error": "..."}
//   binary: a JSON header line {"op": "frame", "topic", "instance", "sensor", "width", "height",
//           "encoding", "stamp_ns", "format": "jpeg"}, '\n', then the JPEG bytes.

#include <cstdint>
#include <optional>
#include <stdexcept>
#include <string>
#include <string_view>
#include <variant>

#include "gui/allow_list.hpp"

namespace concert::gui {

/// Raised for a browser message that does not follow the protocol; the message says what.
class ProtocolError : public std::runtime_error {
 public:
  using std::runtime_error::runtime_error;
};

struct Subscribe {
  std::string topic;
  double max_hz = 0.0;  ///< 0: the topic's default
  std::optional<int64_t> id;
};
struct Unsubscribe {
  std::string topic;
  std::optional<int64_t> id;
};
struct Publish {
  std::string topic;
  Json data;
  std::optional<int64_t> id;
};
struct Ping {
  std::optional<int64_t> id;
};
using ClientMessage = std::variant<Subscribe, Unsubscribe, Publish, Ping>;

/// Parses one text message from the browser. Throws ProtocolError naming the problem (not
/// JSON, not an object, unknown op, a missing or mistyped field).
ClientMessage parse_client_message(std::string_view text);

std::string sample_message(std::string_view topic, std::string_view instance, const Json& data);
std::string error_message(std::string_view error, const std::optional<int64_t>& id);
std::string ack_message(std::string_view topic, const std::optional<int64_t>& id);
/// A binary frame message: `header` as one JSON line, '\n', then `payload`.
std::string frame_message(const Json& header, std::string_view payload);

}  // namespace concert::gui
