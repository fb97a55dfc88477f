#pragma once
// The gateway's core: browser clients, their subscriptions and rate limits, operator commands
// through the allow-list, the latest sample of every state topic for late subscribers, and the
// rate of every topic. No DDS and no sockets: the DDS adapter feeds it samples (decoded only when
// some client will get them) and implements Bus; the web server implements ClientSink.

#include <cstdint>
#include <functional>
#include <map>
#include <memory>
#include <mutex>
#include <optional>
#include <ostream>
#include <set>
#include <string>
#include <string_view>
#include <vector>

#include "gui/allow_list.hpp"
#include "gui/auth.hpp"
#include "gui/client_sink.hpp"
#include "gui/protocol.hpp"
#include "gui/rate_limiter.hpp"

namespace concert::gui {

/// How the gateway forwards a topic.
enum class TopicKind {
  kState,    ///< latched state: every sample, the latest per instance kept for late subscribers
  kStream,   ///< high-rate stream: rate-limited per client, newest sample wins
  kImage,    ///< camera images: compressed frames (binary), rate-limited per client
  kCommand,  ///< commands and requests: every sample
};

struct TopicEntry {
  std::string name;
  std::string type;         ///< IDL type name
  TopicKind kind;
  std::string description;
};

struct HubParams {
  double stream_default_hz = 10.0;  ///< a stream subscription without max_hz [Hz]
  double stream_max_hz = 30.0;      ///< the most a client may ask of a stream [Hz]
  double image_default_hz = 2.0;    ///< camera frames without max_hz [Hz]
  double image_max_hz = 10.0;       ///< the most a client may ask of a camera [Hz]
  /// A client whose socket holds more than this unsent [bytes] gets no stream samples or
  /// frames until it drains (state and command samples are always sent).
  size_t max_buffered_bytes = 4u << 20;
  /// The gateway's heartbeat to every client [ms]: the app shows every state "unknown" after
  /// 1 s without a message from the gateway.
  int heartbeat_ms = 250;
  /// State topics whose instances keep the sample with the newest `stamp_ns`, not the last to
  /// arrive: the e-stop inputs, written by several processes, where a late reader may be handed
  /// an old writer's history after a newer release.
  std::vector<std::string> newest_stamp_topics = {"concert/safety/estop"};
  /// A state topic keeps the latest sample of at most this many instances for late
  /// subscribers, the least recently updated dropped first. The per-request topics (a plan
  /// result with its path per request, a trajectory's, a mission's status) get a new instance
  /// with every request: unbounded, the cache would grow with every request for good.
  /// Topics keyed by service, sensor or e-stop source have far fewer instances. 64 is what
  /// the writers keep registered (concert/dds kLiveInstances).
  std::size_t max_instances_kept = 64;
};

/// The DDS side, implemented by the adapter.
class Bus {
 public:
  virtual ~Bus() = default;
  /// Publishes `sample` (a JSON object of the topic's type, fields may be left out) on `topic`.
  /// Throws std::exception with the reason (e.g. a field the type does not have).
  virtual void publish(const std::string& topic, const Json& sample) = 0;
  /// Whether some client wants `topic` (the adapter subscribes to camera images only then).
  virtual void set_wanted(const std::string& topic, bool wanted) = 0;
};

struct TopicRate {
  std::string topic;
  double hz = 0.0;
  uint64_t count = 0;
  double age_s = -1.0;  ///< since the last sample; -1: none yet
};

/// Thread-safe: DDS threads, the web server's thread and timers may call it concurrently.
class Hub {
 public:
  Hub(std::vector<TopicEntry> topics, HubParams params, std::ostream& log);

  void attach(Bus* bus, ClientSink* sink);
  /// Requires every client to sign in with `auth` (nullptr: none required, every client is the
  /// local engineer: a gateway that serves this machine only). `pairing`: codes are offered.
  void require_auth(Auth* auth, bool pairing);

  /// A new browser connection `client` from `origin` (e.g. "192.168.1.20:51544"); sends it
  /// "hello". Ids are the web server's, never reused.
  void connect(ClientId client, const std::string& origin);
  void disconnect(ClientId client);
  /// One text message from a client; answers (ack, error, samples) through the sink.
  void on_message(ClientId client, std::string_view text, int64_t now_ns);

  /// A sample of `topic` arrived; `decode` gives it as JSON and is called at most once, only
  /// when a client gets it now or the topic is a state topic. `instance` names the DDS instance.
  void on_sample(std::string_view topic, std::string_view instance,
                 const std::function<Json()>& decode, int64_t now_ns);
  /// A camera image arrived; `encode` gives the binary frame message (see protocol.hpp) or
  /// nullopt when the image cannot be shown, and is called at most once, only when due.
  void on_frame(std::string_view topic, std::string_view instance,
                const std::function<std::optional<std::string>()>& encode, int64_t now_ns);

  /// Every topic's rate, count and age (the Topics page).
  std::vector<TopicRate> rates(int64_t now_ns) const;
  /// Sends {"op": "rates", ...} to every client.
  void broadcast_rates(int64_t now_ns);
  /// Sends {"op": "heartbeat"} to every client and signs out expired sessions. `wall_ns` is the
  /// Unix time (sessions expire by it).
  void heartbeat(int64_t wall_ns);

  /// Whether a client is subscribed to `topic`.
  bool wanted(std::string_view topic) const;
  size_t client_count() const;
  /// Commands published / refused since the start.
  uint64_t commands_published() const;
  uint64_t commands_refused() const;
  /// Stream samples and frames not sent to a client because of its rate limit or backlog.
  uint64_t dropped() const;

 private:
  struct Subscription {
    double max_hz = 0.0;
    std::map<std::string, RateLimiter, std::less<>> per_instance;
  };
  struct Client {
    std::string origin;
    std::map<std::string, Subscription, std::less<>> subscriptions;
    std::optional<Session> session;  ///< signed in (always, when no auth is required)
  };
  struct Topic {
    TopicEntry entry;
    RateMeter meter;
    struct Kept {
      std::string message;            // the sample message as sent: a few times smaller than its Json
      std::optional<int64_t> stamp;   // its data's stamp_ns, when it has one
      uint64_t update = 0;            // Hub::updates_ when it was kept
    };
    std::map<std::string, Kept, std::less<>> latest;  // state topics: per instance
    bool newest_stamp = false;                         // keep the newest stamp_ns per instance
  };

  void disconnect_locked(ClientId client);
  struct PendingCommand {
    std::string topic;
    Json sample;
    std::optional<int64_t> request;
    std::string origin;
  };
  std::optional<PendingCommand> on_message_locked(ClientId id, const ClientMessage& message, int64_t now_ns);
  void sign_in(ClientId id, const ClientMessage& message, int64_t now_ns);
  void unsubscribe_all_locked(Client& client);
  /// Signs `client` out (told why, its subscriptions dropped) when its session ended by `now_ns`.
  void expire_locked(ClientId id, Client& client, int64_t now_ns);
  static std::string who(const Client& client);
  void flush_wanted();
  void handle(ClientId id, Client& client, const Subscribe& s, int64_t now_ns);
  void send_locked(ClientId client, std::string message, bool binary);
  std::vector<ClientId> due_locked(Topic& topic, std::string_view instance, int64_t now_ns);
  void refuse_locked(ClientId id, const Client& client, std::string_view topic, const std::string& why,
                     const std::optional<int64_t>& request);

  HubParams params_;
  std::ostream& log_;
  mutable std::mutex mutex_;
  Bus* bus_ = nullptr;
  ClientSink* sink_ = nullptr;
  Auth* auth_ = nullptr;
  bool pairing_ = false;
  std::map<std::string, Topic, std::less<>> topics_;
  std::map<ClientId, Client> clients_;
  uint64_t published_ = 0, refused_ = 0, dropped_ = 0;
  uint64_t updates_ = 0;  // state samples kept so far (the order of Topic::latest's updates)
  std::vector<std::pair<std::string, bool>> wanted_changes_;  // for the bus, outside the lock
};

std::string_view to_string(TopicKind kind);

}  // namespace concert::gui
