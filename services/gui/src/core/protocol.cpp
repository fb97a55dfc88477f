#include "gui/protocol.hpp"

namespace concert::gui {

namespace {

std::optional<int64_t> id_of(const Json& j) {
  if (!j.contains("id")) return std::nullopt;
  if (!j["id"].is_number_integer()) throw ProtocolError("field 'id' must be an integer");
  return j["id"].get<int64_t>();
}

std::string topic_of(const Json& j, std::string_view op) {
  if (!j.contains("topic")) throw ProtocolError("'" + std::string(op) + "' needs a 'topic'");
  if (!j["topic"].is_string() || j["topic"].get<std::string>().empty()) {
    throw ProtocolError("'" + std::string(op) + "': 'topic' must be a non-empty string");
  }
  return j["topic"].get<std::string>();
}

}  // namespace

ClientMessage parse_client_message(std::string_view text) {
  if (text.size() > kMaxClientMessageBytes) {
    throw ProtocolError("message of " + std::to_string(text.size()) + " bytes refused: at most " +
                        std::to_string(kMaxClientMessageBytes));
  }
  Json j;
  try {
    j = Json::parse(text);
  } catch (const Json::exception& e) {
    // parse_error, and out_of_range for a number beyond double (e.g. 1e400): either way a
    // message the browser got wrong, answered with the reason, never thrown at the web server.
    throw ProtocolError(std::string("message is not JSON: ") + e.what());
  }
  if (!j.is_object()) throw ProtocolError("message must be a JSON object, got " + std::string(j.type_name()));
  if (!j.contains("op") || !j["op"].is_string()) throw ProtocolError("message needs a string 'op'");
  const std::string op = j["op"].get<std::string>();
  if (op == "subscribe") {
    Subscribe s{topic_of(j, op), 0.0, id_of(j)};
    if (j.contains("max_hz")) {
      if (!j["max_hz"].is_number() || j["max_hz"].get<double>() < 0) {
        throw ProtocolError("'subscribe': 'max_hz' must be a number >= 0");
      }
      s.max_hz = j["max_hz"].get<double>();
    }
    return s;
  }
  if (op == "unsubscribe") return Unsubscribe{topic_of(j, op), id_of(j)};
  if (op == "publish") {
    Publish p{topic_of(j, op), Json::object(), id_of(j)};
    if (j.contains("data")) p.data = j["data"];
    if (!p.data.is_object()) throw ProtocolError("'publish': 'data' must be a JSON object");
    return p;
  }
  if (op == "ping") return Ping{id_of(j)};
  const auto string_field = [&](const char* name) {
    if (!j.contains(name)) return std::string();
    if (!j[name].is_string()) throw ProtocolError("'" + op + "': '" + name + "' must be a string");
    return j[name].get<std::string>();
  };
  if (op == "login") {
    Login l{string_field("user"), string_field("password"), string_field("token"), id_of(j)};
    if (l.token.empty() && l.user.empty()) throw ProtocolError("'login' needs a 'user' and 'password', or a 'token'");
    return l;
  }
  if (op == "pair") {
    Pair p{string_field("code"), id_of(j)};
    if (p.code.empty()) throw ProtocolError("'pair' needs a 'code'");
    return p;
  }
  if (op == "logout") return Logout{id_of(j)};
  throw ProtocolError("unknown op '" + op + "' (subscribe, unsubscribe, publish, ping, login, pair, logout)");
}

std::string sample_message(std::string_view topic, std::string_view instance, const Json& data) {
  Json m = {{"op", "sample"}, {"topic", topic}, {"instance", instance}, {"data", data}};
  return m.dump(-1, ' ', false, Json::error_handler_t::replace);
}

std::string error_message(std::string_view error, const std::optional<int64_t>& id, double retry_after_s) {
  Json m = {{"op", "error"}};
  if (id) m["id"] = *id;
  m["error"] = error;
  if (retry_after_s > 0) m["retry_after_s"] = retry_after_s;
  return m.dump(-1, ' ', false, Json::error_handler_t::replace);
}

std::string ack_message(std::string_view topic, const std::optional<int64_t>& id) {
  Json m = {{"op", "ack"}};
  if (id) m["id"] = *id;
  m["topic"] = topic;
  return m.dump();
}

std::string frame_message(const Json& header, std::string_view payload) {
  std::string out = header.dump(-1, ' ', false, Json::error_handler_t::replace);
  out += '\n';
  out.append(payload);
  return out;
}

}  // namespace concert::gui
