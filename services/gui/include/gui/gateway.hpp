#pragma once
// The whole gateway: DDS participant + bridge + hub + web server, until `stop`. Used by
// concert_gui's main and by `concert gui`.

#include <atomic>
#include <cstdint>
#include <ostream>
#include <string>
#include <vector>

#include "gui/auth.hpp"
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
  /// HTTPS/WSS: a PKI folder made by `concert security init` (its gui/https_{cert,key}.pem), or
  /// the site's certificate and key. Required for any bind beyond loopback.
  std::string tls_dir;
  std::string tls_certificate;
  std::string tls_key;
  /// Sign-in: always beyond loopback; on loopback only with `auth`.
  bool auth = false;
  std::string users_file;  ///< empty: default_users_file()
  bool pairing = false;    ///< print a one-time pairing code (role: auth.pairing_role)
  AuthParams auth_params;
  HubParams hub;
  JpegParams jpeg;
};

/// Serves until `stop` is set (or `duration_s` passed); prints the address on `out` and logs
/// clients and commands on `log`. Throws std::runtime_error with the reason when it cannot start
/// (the port is taken, the app folder has no index.html, ...).
int run_gateway(const GatewayOptions& options, const std::atomic<bool>& stop, std::ostream& out, std::ostream& log);

/// The default folder of the built app (the build tree's), compiled in.
std::string default_app_dir();

/// The users file: $CONCERT_GUI_USERS, else $XDG_CONFIG_HOME/concert/gui_users.json, else
/// ~/.config/concert/gui_users.json.
std::string default_users_file();

/// Whether `bind` serves this machine only (127.0.0.0/8, ::1, localhost).
bool loopback_only(const std::string& bind);

}  // namespace concert::gui
