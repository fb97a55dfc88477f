#include "gui/hub.hpp"

#include <algorithm>
#include <variant>

#include "gui/protocol.hpp"

namespace concert::gui {

std::string_view to_string(TopicKind kind) {
  switch (kind) {
    case TopicKind::kState: return "state";
    case TopicKind::kStream: return "stream";
    case TopicKind::kImage: return "image";
    case TopicKind::kCommand: return "command";
  }
  return "?";
}

Hub::Hub(std::vector<TopicEntry> topics, HubParams params, std::ostream& log)
    : params_(params), log_(log) {
  for (auto& t : topics) {
    std::string name = t.name;
    const bool newest = std::find(params_.newest_stamp_topics.begin(), params_.newest_stamp_topics.end(), name) !=
                        params_.newest_stamp_topics.end();
    topics_.emplace(std::move(name), Topic{std::move(t), RateMeter{}, {}, newest});
  }
}

void Hub::attach(Bus* bus, ClientSink* sink) {
  std::lock_guard lock(mutex_);
  bus_ = bus;
  sink_ = sink;
}

void Hub::require_auth(Auth* auth, bool pairing) {
  std::lock_guard lock(mutex_);
  auth_ = auth;
  pairing_ = auth != nullptr && pairing;
}

std::string Hub::who(const Client& client) {
  if (!client.session) return "not signed in";
  return "user " + client.session->user + "/" + std::string(to_string(client.session->role));
}

void Hub::send_locked(ClientId client, std::string message, bool binary) {
  if (sink_ != nullptr) sink_->send(client, std::move(message), binary);
}

void Hub::connect(ClientId id, const std::string& origin) {
  std::lock_guard lock(mutex_);
  Client& client = clients_[id];
  client.origin = origin;
  if (auth_ == nullptr) client.session = Session{"", "local", Role::kEngineer, INT64_MAX};
  Json topics = Json::array();
  for (const auto& [name, t] : topics_) {
    topics.push_back({{"topic", name},
                      {"type", t.entry.type},
                      {"kind", to_string(t.entry.kind)},
                      {"commandable", find_operator_command(name) != nullptr},
                      {"description", t.entry.description}});
  }
  Json commands = Json::array();
  for (const auto& c : operator_commands()) {
    commands.push_back({{"topic", c.topic},
                        {"what", c.what},
                        {"available", topics_.count(std::string(c.topic)) > 0},
                        {"fixed", Json::parse(c.fixed_json)},
                        {"role", to_string(c.role)}});
  }
  Json hello = {{"op", "hello"},
                      {"client", origin},
                      {"topics", topics},
                      {"commands", commands},
                      {"limits",
                       {{"stream_default_hz", params_.stream_default_hz},
                        {"stream_max_hz", params_.stream_max_hz},
                        {"image_default_hz", params_.image_default_hz},
                        {"image_max_hz", params_.image_max_hz}}},
                      {"auth", {{"required", auth_ != nullptr}, {"pairing", pairing_}}},
                      {"heartbeat_ms", params_.heartbeat_ms}};
  if (auth_ == nullptr) hello["session"] = {{"user", "local"}, {"role", "engineer"}};
  log_ << "concert_gui: client " << id << " connected from " << origin << std::endl;
  send_locked(id, hello.dump(), false);
}

void Hub::disconnect(ClientId client) {
  disconnect_locked(client);
  flush_wanted();
}

void Hub::flush_wanted() {
  std::vector<std::pair<std::string, bool>> changes;
  Bus* bus = nullptr;
  {
    std::lock_guard lock(mutex_);
    changes.swap(wanted_changes_);
    bus = bus_;
  }
  // Outside the lock: the bus may wait for its DDS listeners, which call into the hub.
  if (bus != nullptr) {
    for (const auto& [topic, wanted] : changes) bus->set_wanted(topic, wanted);
  }
}

void Hub::disconnect_locked(ClientId client) {
  std::lock_guard lock(mutex_);
  auto it = clients_.find(client);
  if (it == clients_.end()) return;
  const std::string origin = it->second.origin;
  std::vector<std::string> topics;
  for (const auto& [topic, sub] : it->second.subscriptions) topics.push_back(topic);
  clients_.erase(it);
  for (const auto& topic : topics) {
    bool still = false;
    for (const auto& [id, c] : clients_) still = still || c.subscriptions.count(topic) > 0;
    if (!still) wanted_changes_.emplace_back(topic, false);
  }
  log_ << "concert_gui: client " << client << " (" << origin << ") disconnected" << std::endl;
}

void Hub::handle(ClientId id, Client& client, const Subscribe& s, int64_t /*now_ns*/) {
  auto t = topics_.find(s.topic);
  if (t == topics_.end()) {
    send_locked(id, error_message("no topic '" + s.topic + "' in the catalogue", s.id), false);
    return;
  }
  const TopicKind kind = t->second.entry.kind;
  double hz = 0.0;  // no limit: state and command topics get every sample
  if (kind == TopicKind::kStream) {
    hz = s.max_hz > 0 ? std::min(s.max_hz, params_.stream_max_hz) : params_.stream_default_hz;
  } else if (kind == TopicKind::kImage) {
    hz = s.max_hz > 0 ? std::min(s.max_hz, params_.image_max_hz) : params_.image_default_hz;
  }
  const bool first = std::none_of(clients_.begin(), clients_.end(),
                                  [&](const auto& c) { return c.second.subscriptions.count(s.topic) > 0; });
  client.subscriptions[s.topic] = Subscription{hz, {}};
  Json ack = {{"op", "ack"}, {"topic", s.topic}, {"max_hz", hz}};
  if (s.id) ack["id"] = *s.id;
  send_locked(id, ack.dump(), false);
  for (const auto& [instance, kept] : t->second.latest) send_locked(id, kept.message, false);
  if (first) wanted_changes_.emplace_back(s.topic, true);
}

void Hub::refuse_locked(ClientId id, const Client& client, std::string_view topic, const std::string& why,
                        const std::optional<int64_t>& request) {
  ++refused_;
  log_ << "concert_gui: command REFUSED from " << client.origin << " (client " << id << ", " << who(client)
       << ") on " << topic << ": " << why << std::endl;
  send_locked(id, error_message(why, request), false);
}

void Hub::on_message(ClientId id, std::string_view text, int64_t now_ns) {
  ClientMessage message;
  try {
    message = parse_client_message(text);
  } catch (const ProtocolError& e) {
    std::lock_guard lock(mutex_);
    auto c = clients_.find(id);
    if (c == clients_.end()) return;
    log_ << "concert_gui: message REFUSED from " << c->second.origin << " (client " << id << "): " << e.what()
         << std::endl;
    send_locked(id, error_message(e.what(), std::nullopt), false);
    return;
  }
  if (std::holds_alternative<Login>(message) || std::holds_alternative<Pair>(message)) {
    sign_in(id, message, now_ns);
    return;
  }
  const std::optional<PendingCommand> command = on_message_locked(id, message, now_ns);
  flush_wanted();
  if (!command) return;
  // Published outside the lock: a DDS writer may deliver to this process's own readers on the
  // calling thread, and their samples come back into the hub.
  Bus* bus = nullptr;
  {
    std::lock_guard lock(mutex_);
    bus = bus_;
  }
  std::string error;
  try {
    if (bus == nullptr) throw std::runtime_error("the gateway is stopping");
    bus->publish(command->topic, command->sample);
  } catch (const std::exception& e) {
    error = e.what();
  }
  std::lock_guard lock(mutex_);
  auto c = clients_.find(id);
  if (!error.empty()) {
    const std::string why = "command on '" + command->topic + "' not sent: " + error;
    ++refused_;
    log_ << "concert_gui: command REFUSED from " << command->origin << " (client " << id << ") on "
         << command->topic << ": " << why << std::endl;
    if (c != clients_.end()) send_locked(id, error_message(why, command->request), false);
    return;
  }
  ++published_;
  log_ << "concert_gui: command from " << command->origin << " (client " << id << ", "
       << (c != clients_.end() ? who(c->second) : "gone") << ") on " << command->topic << ": "
       << command->sample.dump() << std::endl;
  if (c != clients_.end()) send_locked(id, ack_message(command->topic, command->request), false);
}

void Hub::sign_in(ClientId id, const ClientMessage& message, int64_t now_ns) {
  Auth* auth = nullptr;
  std::string origin;
  {
    std::lock_guard lock(mutex_);
    auto c = clients_.find(id);
    if (c == clients_.end()) return;
    auth = auth_;
    origin = c->second.origin;
  }
  const auto* login = std::get_if<Login>(&message);
  const auto* pair = std::get_if<Pair>(&message);
  const std::optional<int64_t> request = login != nullptr ? login->id : pair->id;
  const std::string address = address_of(origin);
  std::optional<Session> session;
  std::string why;
  double retry = 0.0;
  if (auth == nullptr) {
    why = "this gateway requires no sign-in (it serves this machine only)";
  } else {
    // Outside the hub's lock: a password check costs argon2id's tenth of a second, and the DDS
    // threads must not wait for it.
    try {
      if (pair != nullptr) {
        session = auth->pair(address, pair->code, now_ns);
      } else if (!login->token.empty()) {
        session = auth->resume(address, login->token, now_ns);
      } else {
        session = auth->sign_in(address, login->user, login->password, now_ns);
      }
    } catch (const SignInRefused& e) {
      why = e.what();
      retry = e.retry_after_s;
    }
  }
  std::lock_guard lock(mutex_);
  auto c = clients_.find(id);
  if (c == clients_.end()) return;
  if (!session) {
    log_ << "concert_gui: sign-in REFUSED from " << origin << " (client " << id << ")"
         << (login != nullptr && !login->user.empty() ? " as '" + login->user + "'" : "") << ": " << why << std::endl;
    send_locked(id, error_message(why, request, retry), false);
    return;
  }
  if (pair != nullptr) {
    log_ << "concert_gui: pairing code used by " << origin << "; a new code: " << auth->new_pairing_code(now_ns)
         << std::endl;
  }
  c->second.session = session;
  log_ << "concert_gui: client " << id << " (" << origin << ") signed in as " << session->user << " ("
       << to_string(session->role) << ")" << std::endl;
  Json m = {{"op", "session"},
            {"user", session->user},
            {"role", to_string(session->role)},
            {"token", session->token},
            {"expires_in_s", std::max<int64_t>(0, (session->expires_ns - now_ns) / 1'000'000'000)}};
  if (request) m["id"] = *request;
  send_locked(id, m.dump(-1, ' ', false, Json::error_handler_t::replace), false);
}

void Hub::expire_locked(ClientId id, Client& client, int64_t now_ns) {
  if (auth_ == nullptr || !client.session || client.session->expires_ns > now_ns) return;
  log_ << "concert_gui: client " << id << " (" << client.origin << "): session of " << client.session->user
       << " expired" << std::endl;
  client.session.reset();
  unsubscribe_all_locked(client);
  send_locked(id, Json{{"op", "signed_out"}, {"reason", "session expired: sign in again"}}.dump(), false);
}

void Hub::unsubscribe_all_locked(Client& client) {
  for (const auto& [topic, sub] : client.subscriptions) {
    bool still = false;
    for (const auto& [other, c] : clients_) still = still || (&c != &client && c.subscriptions.count(topic) > 0);
    if (!still) wanted_changes_.emplace_back(topic, false);
  }
  client.subscriptions.clear();
}

std::optional<Hub::PendingCommand> Hub::on_message_locked(ClientId id, const ClientMessage& message, int64_t now_ns) {
  std::lock_guard lock(mutex_);
  auto c = clients_.find(id);
  if (c == clients_.end()) return std::nullopt;
  Client& client = c->second;
  expire_locked(id, client, now_ns);
  if (const auto* g = std::get_if<Ping>(&message)) {
    Json pong = {{"op", "pong"}};
    if (g->id) pong["id"] = *g->id;
    send_locked(id, pong.dump(), false);
    return std::nullopt;
  }
  if (const auto* o = std::get_if<Logout>(&message)) {
    if (auth_ != nullptr && client.session) {
      auth_->sign_out(client.session->token);
      log_ << "concert_gui: client " << id << " (" << client.origin << ") signed out (" << who(client) << ")"
           << std::endl;
      client.session.reset();
      unsubscribe_all_locked(client);
    }
    Json m = {{"op", "signed_out"}, {"reason", auth_ != nullptr ? "signed out" : "no sign-in on this gateway"}};
    if (o->id) m["id"] = *o->id;
    send_locked(id, m.dump(), false);
    return std::nullopt;
  }
  if (!client.session) {
    const auto* p = std::get_if<Publish>(&message);
    const auto* s = std::get_if<Subscribe>(&message);
    const auto* u = std::get_if<Unsubscribe>(&message);
    const std::optional<int64_t> request = p ? p->id : s ? s->id : u ? u->id : std::nullopt;
    if (p != nullptr) {
      refuse_locked(id, client, p->topic, "sign in first: this gateway takes commands from signed-in users only",
                    request);
    } else {
      send_locked(id, error_message("sign in first: this gateway shows the robot to signed-in users only", request),
                  false);
    }
    return std::nullopt;
  }
  if (const auto* s = std::get_if<Subscribe>(&message)) {
    handle(id, client, *s, now_ns);
  } else if (const auto* u = std::get_if<Unsubscribe>(&message)) {
    client.subscriptions.erase(u->topic);
    const bool still = std::any_of(clients_.begin(), clients_.end(),
                                   [&](const auto& o) { return o.second.subscriptions.count(u->topic) > 0; });
    if (!still) wanted_changes_.emplace_back(u->topic, false);
    send_locked(id, ack_message(u->topic, u->id), false);
  } else if (const auto* p = std::get_if<Publish>(&message)) {
    Json sample;
    try {
      check_role(p->topic, client.session->role);
      sample = admit_command(p->topic, p->data, client.origin, now_ns);
    } catch (const CommandRefused& e) {
      refuse_locked(id, client, p->topic, e.what(), p->id);
      return std::nullopt;
    }
    if (topics_.count(p->topic) == 0 || bus_ == nullptr) {
      refuse_locked(id, client, p->topic, "'" + p->topic + "' is not in this build's catalogue", p->id);
      return std::nullopt;
    }
    return PendingCommand{p->topic, std::move(sample), p->id, client.origin};
  }
  return std::nullopt;
}

std::vector<ClientId> Hub::due_locked(Topic& topic, std::string_view instance, int64_t now_ns) {
  std::vector<ClientId> due;
  const bool limited = topic.entry.kind == TopicKind::kStream || topic.entry.kind == TopicKind::kImage;
  for (auto& [id, client] : clients_) {
    auto s = client.subscriptions.find(topic.entry.name);
    if (s == client.subscriptions.end()) continue;
    if (limited) {
      if (sink_ != nullptr && sink_->buffered_bytes(id) > params_.max_buffered_bytes) {
        ++dropped_;
        continue;
      }
      auto l = s->second.per_instance.find(instance);
      if (l == s->second.per_instance.end()) {
        l = s->second.per_instance.emplace(std::string(instance), RateLimiter(s->second.max_hz)).first;
      }
      if (!l->second.admit(now_ns)) {
        ++dropped_;
        continue;
      }
    }
    due.push_back(id);
  }
  return due;
}

void Hub::on_sample(std::string_view topic_name, std::string_view instance,
                    const std::function<Json()>& decode, int64_t now_ns) {
  std::lock_guard lock(mutex_);
  auto t = topics_.find(topic_name);
  if (t == topics_.end()) return;
  Topic& topic = t->second;
  topic.meter.add(now_ns);
  const std::vector<ClientId> due = due_locked(topic, instance, now_ns);
  const bool state = topic.entry.kind == TopicKind::kState;
  if (due.empty() && !state) return;
  Json data;
  try {
    data = decode();
  } catch (const std::exception& e) {
    log_ << "concert_gui: a sample of " << topic_name << " does not decode: " << e.what() << std::endl;
    return;
  }
  std::string message = sample_message(topic_name, instance, data);
  if (state) {
    std::optional<int64_t> stamp;
    if (data.contains("stamp_ns") && data["stamp_ns"].is_number()) stamp = data["stamp_ns"].get<int64_t>();
    auto kept = topic.latest.find(instance);
    if (topic.newest_stamp && kept != topic.latest.end() && stamp && kept->second.stamp &&
        *stamp < *kept->second.stamp) {
      // An older sample than the one kept (another writer's history handed to a late reader):
      // neither kept nor shown.
      return;
    }
    if (kept == topic.latest.end() && params_.max_instances_kept > 0 &&
        topic.latest.size() >= params_.max_instances_kept) {
      // A new instance on a full topic: the least recently updated one makes room.
      const auto oldest = std::min_element(topic.latest.begin(), topic.latest.end(), [](const auto& a, const auto& b) {
        return a.second.update < b.second.update;
      });
      topic.latest.erase(oldest);
    }
    for (ClientId id : due) send_locked(id, message, false);
    topic.latest[std::string(instance)] = {std::move(message), stamp, ++updates_};
    return;
  }
  for (ClientId id : due) send_locked(id, message, false);
}

void Hub::on_frame(std::string_view topic_name, std::string_view instance,
                   const std::function<std::optional<std::string>()>& encode, int64_t now_ns) {
  std::lock_guard lock(mutex_);
  auto t = topics_.find(topic_name);
  if (t == topics_.end()) return;
  t->second.meter.add(now_ns);
  const std::vector<ClientId> due = due_locked(t->second, instance, now_ns);
  if (due.empty()) return;
  const std::optional<std::string> frame = encode();
  if (!frame) return;
  for (ClientId id : due) send_locked(id, *frame, true);
}

std::vector<TopicRate> Hub::rates(int64_t now_ns) const {
  std::lock_guard lock(mutex_);
  std::vector<TopicRate> out;
  for (const auto& [name, t] : topics_) {
    TopicRate r{name, t.meter.hz(now_ns), t.meter.count(), -1.0};
    if (t.meter.count() > 0) r.age_s = static_cast<double>(now_ns - t.meter.last_ns()) * 1e-9;
    out.push_back(r);
  }
  return out;
}

void Hub::broadcast_rates(int64_t now_ns) {
  Json list = Json::array();
  for (const auto& r : rates(now_ns)) {
    list.push_back({{"topic", r.topic}, {"hz", r.hz}, {"count", r.count}, {"age_s", r.age_s}});
  }
  const std::string message = Json{{"op", "rates"}, {"topics", list}}.dump();
  std::lock_guard lock(mutex_);
  for (const auto& [id, c] : clients_) {
    if (c.session) send_locked(id, message, false);
  }
}

void Hub::heartbeat(int64_t wall_ns) {
  {
    std::lock_guard lock(mutex_);
    const std::string beat = Json{{"op", "heartbeat"}, {"now_ms", wall_ns / 1'000'000}}.dump();
    for (auto& [id, c] : clients_) {
      expire_locked(id, c, wall_ns);
      send_locked(id, beat, false);
    }
  }
  flush_wanted();
}

bool Hub::wanted(std::string_view topic) const {
  std::lock_guard lock(mutex_);
  return std::any_of(clients_.begin(), clients_.end(),
                     [&](const auto& c) { return c.second.subscriptions.count(std::string(topic)) > 0; });
}

size_t Hub::client_count() const {
  std::lock_guard lock(mutex_);
  return clients_.size();
}

uint64_t Hub::commands_published() const {
  std::lock_guard lock(mutex_);
  return published_;
}

uint64_t Hub::commands_refused() const {
  std::lock_guard lock(mutex_);
  return refused_;
}

uint64_t Hub::dropped() const {
  std::lock_guard lock(mutex_);
  return dropped_;
}

}  // namespace concert::gui
