#include "gui/gateway.hpp"

#include <chrono>
#include <cstdlib>
#include <memory>
#include <filesystem>
#include <stdexcept>
#include <thread>

#include "concert/dds/participant.hpp"
#include "dds/bridge.hpp"
#include "gui/web_server.hpp"

namespace concert::gui {

namespace fs = std::filesystem;

std::string default_app_dir() { return CONCERT_GUI_APP_DIR; }

std::string default_users_file() {
  if (const char* f = std::getenv("CONCERT_GUI_USERS"); f != nullptr && *f != '\0') return f;
  if (const char* x = std::getenv("XDG_CONFIG_HOME"); x != nullptr && *x != '\0') {
    return (fs::path(x) / "concert" / "gui_users.json").string();
  }
  const char* home = std::getenv("HOME");
  return (fs::path(home != nullptr ? home : ".") / ".config" / "concert" / "gui_users.json").string();
}

bool loopback_only(const std::string& bind) {
  return bind == "localhost" || bind == "::1" || bind.rfind("127.", 0) == 0;
}

namespace {

int64_t wall_ns() {
  return std::chrono::duration_cast<std::chrono::nanoseconds>(std::chrono::system_clock::now().time_since_epoch())
      .count();
}

/// The web server's options: the app and module database folders, and HTTPS (a PKI folder's
/// certificate or the site's), refused when plain HTTP would serve beyond this machine.
WebServerOptions web_options(const GatewayOptions& o, uint16_t port) {
  WebServerOptions web{o.bind, port, {}};
  if (!o.tls_dir.empty()) {
    if (!o.tls_certificate.empty() || !o.tls_key.empty()) {
      throw std::runtime_error("--tls DIR and --tls-cert/--tls-key: give one or the other");
    }
    web.tls_certificate = (fs::path(o.tls_dir) / "gui" / "https_cert.pem").string();
    web.tls_key = (fs::path(o.tls_dir) / "gui" / "https_key.pem").string();
    if (!fs::is_regular_file(web.tls_certificate)) {
      throw std::runtime_error("--tls " + o.tls_dir + ": no gui/https_cert.pem (made by `concert security init`; "
                               "`concert security https DIR --name HOST` makes one for this host)");
    }
  } else {
    web.tls_certificate = o.tls_certificate;
    web.tls_key = o.tls_key;
  }
  if (!loopback_only(o.bind) && web.tls_certificate.empty()) {
    throw std::runtime_error("--bind " + o.bind +
                             ": serving beyond this machine needs HTTPS, refused over plain HTTP (give --tls DIR, "
                             "a folder made by `concert security init`, or --tls-cert/--tls-key)");
  }
  web.roots.app = o.app_dir.empty() ? default_app_dir() : o.app_dir;
  if (!fs::is_regular_file(web.roots.app / "index.html")) {
    throw std::runtime_error("--app " + web.roots.app.string() +
                             ": no index.html (build the app: cmake --build build --target concert_gui_app)");
  }
  for (const auto& db : o.module_dbs) {
    if (!fs::is_directory(db)) throw std::runtime_error("--module-db " + db + ": no such folder");
    auto [name, dir] = package_of(fs::absolute(db));
    web.roots.packages[name] = dir;
  }
  return web;
}

/// Sign-in, when required (beyond loopback, or --auth): the users of `users_file`; a gateway
/// nobody could sign in to (no users, no pairing) is refused at start.
std::unique_ptr<Auth> make_auth(const GatewayOptions& o, const std::string& users_file) {
  if (!o.auth && loopback_only(o.bind)) return nullptr;
  auto auth = std::make_unique<Auth>(UserStore::load(users_file), o.auth_params);
  if (auth->user_count() == 0 && !o.pairing) {
    throw std::runtime_error("sign-in required but " + users_file +
                             " has no users: add one (concert gui users add NAME --role operator) or give --pairing");
  }
  return auth;
}

}  // namespace

int run_gateway(const GatewayOptions& o, const std::atomic<bool>& stop, std::ostream& out, std::ostream& log) {
  concert::dds::Participant participant({.name = "concert-gui", .domain_id = o.domain_id});
  const int port = o.port >= 0 ? o.port : 8080 + participant.domain_id();
  if (port > 65535) throw std::runtime_error("--port " + std::to_string(port) + ": not a TCP port");
  const WebServerOptions web = web_options(o, static_cast<uint16_t>(port));
  const bool tls = !web.tls_certificate.empty();
  const std::string users_file = o.users_file.empty() ? default_users_file() : o.users_file;
  const std::unique_ptr<Auth> auth = make_auth(o, users_file);
  Hub hub(dds::catalogue_topics(), o.hub, log);
  dds::Bridge bridge(participant, hub, o.jpeg, log);
  WebServer server(web,
                   {[&hub](ClientId id, const std::string& origin) { hub.connect(id, origin); },
                    [&hub](ClientId id, const std::string& text) { hub.on_message(id, text, wall_ns()); },
                    [&hub](ClientId id) { hub.disconnect(id); }},
                   log);
  hub.attach(&bridge, &server);
  hub.require_auth(auth.get(), o.pairing);
  server.every(o.hub.heartbeat_ms, [&hub] { hub.heartbeat(wall_ns()); });
  server.every(1000, [&hub] {
    hub.broadcast_rates(std::chrono::duration_cast<std::chrono::nanoseconds>(
                            std::chrono::steady_clock::now().time_since_epoch())
                            .count());
  });
  server.start();
  const std::string host = o.bind == "0.0.0.0" || o.bind == "::" ? "<this host>" : o.bind;
  const std::string url = std::string(tls ? "https" : "http") + "://" + host + ":" + std::to_string(server.port()) + "/";
  if (o.json) {
    out << Json{{"url", url}, {"bind", o.bind}, {"port", server.port()}, {"domain", participant.domain_id()},
                 {"tls", tls}, {"sign_in", auth != nullptr}}.dump()
        << std::endl;
  } else {
    out << "concert gui: " << url << std::endl;
  }
  log << "concert_gui: serving " << url << " (domain " << participant.domain_id() << ", app "
      << web.roots.app.string() << ")" << std::endl;
  if (auth) {
    log << "concert_gui: sign-in required (" << auth->user_count() << " users in " << users_file << ")"
        << std::endl;
    if (o.pairing) {
      log << "concert_gui: pairing code (one use, " << o.auth_params.pairing_ttl_s << " s, role "
          << to_string(o.auth_params.pairing_role) << "): " << auth->new_pairing_code(wall_ns()) << std::endl;
    }
  } else {
    log << "concert_gui: no sign-in: this machine only (--bind " << o.bind << "), every client is the engineer"
        << std::endl;
  }
  const auto until = std::chrono::steady_clock::now() +
                     std::chrono::duration_cast<std::chrono::steady_clock::duration>(
                         std::chrono::duration<double>(o.duration_s));
  while (!stop && (o.duration_s <= 0 || std::chrono::steady_clock::now() < until)) {
    std::this_thread::sleep_for(std::chrono::milliseconds(100));
  }
  log << "concert_gui: stopping (" << hub.commands_published() << " commands sent, " << hub.commands_refused()
      << " refused)" << std::endl;
  hub.attach(nullptr, nullptr);
  server.stop();
  return 0;
}

}  // namespace concert::gui
