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
    topics_.emplace(std::move(name), Topic{std::move(t), RateMeter{}, {}});
  }
}

void Hub::attach(Bus* bus, ClientSink* sink) {
  std::lock_guard lock(mutex_);
  bus_ = bus;
  sink_ = sink;
}

void Hub::send_locked(ClientId client, std::string message, bool binary) {
  if (sink_ != nullptr) sink_->send(client, std::move(message), binary);
}

void Hub::connect(ClientId id, const std::string& origin) {
  std::lock_guard lock(mutex_);
  clients_[id].origin = origin;
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
                        {"fixed", Json::parse(c.fixed_json)}});
  }
  const Json hello = {{"op", "hello"},
                      {"client", origin},
                      {"topics", topics},
                      {"commands", commands},
                      {"limits",
                       {{"stream_default_hz", params_.stream_default_hz},
                        {"stream_max_hz", params_.stream_max_hz},
                        {"image_default_hz", params_.image_default_hz},
                        {"image_max_hz", params_.image_max_hz}}}};
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
  for (const auto& [instance, data] : t->second.latest) {
    send_locked(id, sample_message(s.topic, instance, data), false);
  }
  if (first) wanted_changes_.emplace_back(s.topic, true);
}

void Hub::refuse_locked(ClientId id, const Client& client, std::string_view topic, const std::string& why,
                        const std::optional<int64_t>& request) {
  ++refused_;
  log_ << "concert_gui: command REFUSED from " << client.origin << " (client " << id << ") on " << topic
       << ": " << why << std::endl;
  send_locked(id, error_message(why, request), false);
}

void Hub::on_message(ClientId id, std::string_view text, int64_t now_ns) {
  const std::optional<PendingCommand> command = on_message_locked(id, text, now_ns);
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
  log_ << "concert_gui: command from " << command->origin << " (client " << id << ") on " << command->topic
       << ": " << command->sample.dump() << std::endl;
  if (c != clients_.end()) send_locked(id, ack_message(command->topic, command->request), false);
}

std::optional<Hub::PendingCommand> Hub::on_message_locked(ClientId id, std::string_view text, int64_t now_ns) {
  std::lock_guard lock(mutex_);
  auto c = clients_.find(id);
  if (c == clients_.end()) return std::nullopt;
  Client& client = c->second;
  ClientMessage message;
  try {
    message = parse_client_message(text);
  } catch (const ProtocolError& e) {
    send_locked(id, error_message(e.what(), std::nullopt), false);
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
  } else if (const auto* g = std::get_if<Ping>(&message)) {
    Json pong = {{"op", "pong"}};
    if (g->id) pong["id"] = *g->id;
    send_locked(id, pong.dump(), false);
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
  if (state) topic.latest[std::string(instance)] = data;
  if (due.empty()) return;
  const std::string message = sample_message(topic_name, instance, data);
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
  for (const auto& [id, c] : clients_) send_locked(id, message, false);
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
