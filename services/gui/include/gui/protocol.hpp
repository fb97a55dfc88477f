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
//   {"op": "login", "user": U, "password": P, "id": N?}       sign in (auth.hpp)
//   {"op": "login", "token": T, "id": N?}                     resume a session (a reloaded page)
//   {"op": "pair", "code": C, "id": N?}                       a one-time pairing code
//   {"op": "logout", "id": N?}
// Gateway -> browser:
//   {"op": "hello", "topics": [...], "commands": [...], "limits": {...}, "client": ORIGIN,
//    "auth": {"required", "pairing"}, "heartbeat_ms": N, "session": {...}?}
//   {"op": "session", "id": N?, "user", "role", "token", "expires_in_s"}   signed in
//   {"op": "signed_out", "reason"}      signed out, or the session expired
//   {"op": "heartbeat", "now_ms"}       every heartbeat_ms: a silent gateway is a stale page
//   {"op": "sample", "topic": T, "instance": K, "data": {...}}  (fields of the IDL type)
//   {"op": "rates", "topics": [{"topic", "hz", "count", "age_s"}...]}   every second
//   {"op": "ack", "id": N, "topic": T}    |   {"op": "error", "id": N?, "error": "...", "retry_after_s"?}
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
struct Login {
  std::string user, password;  ///< a password sign-in
  std::string token;           ///< or a session's token
  std::optional<int64_t> id;
};
struct Pair {
  std::string code;
  std::optional<int64_t> id;
};
struct Logout {
  std::optional<int64_t> id;
};
using ClientMessage = std::variant<Subscribe, Unsubscribe, Publish, Ping, Login, Pair, Logout>;

/// The longest text message a browser may send [bytes]: a mission file or an assembly fits
/// many times; anything longer is refused unread.
inline constexpr size_t kMaxClientMessageBytes = 1u << 20;

/// Parses one text message from the browser. Throws ProtocolError naming the problem (longer
/// than kMaxClientMessageBytes, not JSON, not an object, unknown op, a missing or mistyped
/// field).
ClientMessage parse_client_message(std::string_view text);

std::string sample_message(std::string_view topic, std::string_view instance, const Json& data);
std::string error_message(std::string_view error, const std::optional<int64_t>& id,
                          double retry_after_s = 0.0);
std::string ack_message(std::string_view topic, const std::optional<int64_t>& id);
/// A binary frame message: `header` as one JSON line, '\n', then `payload`.
std::string frame_message(const Json& header, std::string_view payload);

}  // namespace concert::gui
