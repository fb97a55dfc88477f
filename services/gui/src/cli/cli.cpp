#include "gui/cli.hpp"

#include <iostream>
#include <memory>

#include "concert/cli/stop_signals.hpp"

namespace concert::gui {

void add_gateway_options(CLI::App& app, GatewayOptions& o) {
  app.add_option("--port", o.port, "TCP port of the app and its WebSocket API (0: any free port)")
      ->type_name("N")
      ->check(cli::number(0, 65535, true))
      ->default_str("8080 + domain");
  app.add_option("--bind", o.bind,
                 "address to listen on; the default serves this machine only, 0.0.0.0 the robot's "
                 "network (every client there may then send operator commands)")
      ->type_name("ADDR")
      ->default_str(o.bind);
  app.add_option("--app", o.app_dir, "the built app's folder (default: the build tree's)")->type_name("DIR");
  app.add_option("--module-db", o.module_dbs,
                 "module database folder whose meshes the 3D view loads (package://<folder name>/...; "
                 "repeat for several)")
      ->type_name("DIR");
  app.add_option("--stream-hz", o.hub.stream_max_hz, "the most samples a second a browser gets of a stream")
      ->type_name("HZ")
      ->check(cli::number(0.1, 1000.0))
      ->default_str(std::to_string(o.hub.stream_max_hz));
  app.add_option("--image-hz", o.hub.image_max_hz, "the most camera frames a second a browser gets")
      ->type_name("HZ")
      ->check(cli::number(0.1, 60.0))
      ->default_str(std::to_string(o.hub.image_max_hz));
  app.add_option("--jpeg-quality", o.jpeg.quality, "JPEG quality of camera frames (1-100)")
      ->type_name("Q")
      ->check(cli::number(1, 100, true));
}

void register_verbs(cli::Cli& concert) {
  auto o = std::make_shared<GatewayOptions>();
  auto dds = std::make_shared<cli::DdsOptions>();
  CLI::App& verb = concert.verb(concert.app(), "gui",
                                "the operator GUI: serve the web app and bridge it to DDS until Ctrl-C",
                                [&concert, o, dds] {
                                  o->domain_id = dds->domain_id();
                                  o->duration_s = dds->timeout_s;
                                  o->json = dds->json;
                                  return run_gateway(*o, cli::stop_on_signals(), concert.out(), concert.err());
                                });
  add_gateway_options(verb, *o);
  concert.add_dds_options(verb, *dds, 0.0, "serve this long, then stop (0: until Ctrl-C)");
}

}  // namespace concert::gui
