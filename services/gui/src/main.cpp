// concert_gui: the operator GUI's gateway. Serves the web app (services/gui/app, built with
// esbuild) and its WebSocket API, bridging the browser and DDS: catalogue topics to the
// browser as JSON (rate-limited streams, camera images as JPEG), operator commands from the
// allow-list back onto DDS, each logged with the client's address.
//   concert_gui [--port N] [--bind ADDR] [--module-db DIR]... [--app DIR]
// Domain: CONCERT_DOMAIN_ID. Stops on SIGINT/SIGTERM.
#include <iostream>

#include "concert/common/memory.hpp"
#include "concert/cli/cli.hpp"
#include "concert/cli/stop_signals.hpp"
#include "gui/cli.hpp"

int main(int argc, char** argv) {
  concert::fix_malloc_thresholds();  // a heap that does not grow with every hot swap
  concert::cli::Cli cli("concert_gui", "The operator GUI's gateway: web app + WebSocket API over DDS.", std::cout,
                        std::cerr);
  concert::gui::GatewayOptions o;
  auto& app = cli.app();
  concert::gui::add_gateway_options(app, o);
  cli.on_run(app, [&o] { return concert::gui::run_gateway(o, concert::cli::stop_on_signals(), std::cout, std::cerr); });
  return cli.run(argc, argv);
}
