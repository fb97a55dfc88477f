#pragma once
// The whole gateway: DDS participant + bridge + hub + web server, until `stop`. Used by
// concert_gui's main and by `concert gui`.

#include <atomic>
#include <cstdint>
#include <ostream>
#include <string>
#include <vector>

#include "gui/hub.hpp"
#include "gui/image.hpp"

namespace concert::gui {

struct GatewayOptions {
  std::string bind = "127.0.0.1";  ///< localhost only unless told otherwise
  int port = -1;                   ///< -1: 8080 + the DDS domain id (as `concert up` does)
  std::string app_dir;                    ///< the built app (services/gui/app -> build)
  std::vector<std::string> module_dbs;    ///< folders served as URDF packages (meshes)
  int32_t domain_id = -1;                 ///< -1: CONCERT_DOMAIN_ID
  double duration_s = 0.0;                ///< stop after this long [s]; 0: only on `stop`
  bool json = false;                      ///< print the address as a JSON line on `out`
  HubParams hub;
  JpegParams jpeg;
};

/// Serves until `stop` is set (or `duration_s` passed); prints the address on `out` and logs
/// clients and commands on `log`. Throws std::runtime_error with the reason when it cannot start
/// (the port is taken, the app folder has no index.html, ...).
int run_gateway(const GatewayOptions& options, const std::atomic<bool>& stop, std::ostream& out, std::ostream& log);

/// The default folder of the built app (the build tree's), compiled in.
std::string default_app_dir();

}  // namespace concert::gui
