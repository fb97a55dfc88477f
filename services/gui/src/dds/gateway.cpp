#include "gui/gateway.hpp"

#include <chrono>
#include <filesystem>
#include <stdexcept>
#include <thread>

#include "concert/dds/participant.hpp"
#include "dds/bridge.hpp"
#include "gui/web_server.hpp"

namespace concert::gui {

namespace fs = std::filesystem;

std::string default_app_dir() { return CONCERT_GUI_APP_DIR; }

int run_gateway(const GatewayOptions& o, const std::atomic<bool>& stop, std::ostream& out, std::ostream& log) {
  concert::dds::Participant participant({.name = "concert-gui", .domain_id = o.domain_id});
  const int port = o.port >= 0 ? o.port : 8080 + participant.domain_id();
  if (port > 65535) throw std::runtime_error("--port " + std::to_string(port) + ": not a TCP port");
  WebServerOptions web{o.bind, static_cast<uint16_t>(port), {}};
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
  Hub hub(dds::catalogue_topics(), o.hub, log);
  dds::Bridge bridge(participant, hub, o.jpeg, log);
  WebServer server(web,
                   {[&hub](ClientId id, const std::string& origin) { hub.connect(id, origin); },
                    [&hub](ClientId id, const std::string& text) {
                      hub.on_message(id, text,
                                     std::chrono::duration_cast<std::chrono::nanoseconds>(
                                         std::chrono::system_clock::now().time_since_epoch())
                                         .count());
                    },
                    [&hub](ClientId id) { hub.disconnect(id); }},
                   log);
  hub.attach(&bridge, &server);
  server.every(1000, [&hub] {
    hub.broadcast_rates(std::chrono::duration_cast<std::chrono::nanoseconds>(
                            std::chrono::steady_clock::now().time_since_epoch())
                            .count());
  });
  server.start();
  const std::string host = o.bind == "0.0.0.0" ? "<this host>" : o.bind;
  const std::string url = "http://" + host + ":" + std::to_string(server.port()) + "/";
  if (o.json) {
    out << Json{{"url", url}, {"bind", o.bind}, {"port", server.port()}, {"domain", participant.domain_id()}}.dump()
        << std::endl;
  } else {
    out << "concert gui: " << url << std::endl;
  }
  log << "concert_gui: serving " << url << " (domain " << participant.domain_id() << ", app "
      << web.roots.app.string() << ")" << std::endl;
  if (o.bind != "127.0.0.1" && o.bind != "::1" && o.bind != "localhost") {
    log << "concert_gui: listening beyond this machine (--bind " << o.bind
        << "): every client on that network may send operator commands" << std::endl;
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
