#pragma once
// The discovery service's parameters file (config/discovery.yaml lists every key).

#include <string>
#include <vector>

#include "concert/config/config.hpp"

namespace concert::discovery::dds {

struct ServiceParams {
  /// Module database folders, merged in order; empty: the project's database.
  std::vector<std::string> module_dbs;
  /// Frame processing order of the ESC ports: "0312" (real hardware) or "0123".
  std::string port_order = "0312";
};

/// Reads the parameters of `doc` (`module_db` may be one folder or a list), starting from the
/// defaults. Throws config::ConfigError naming the file, the key and the line.
ServiceParams read_service_params(config::Document& doc);
ServiceParams load_service_params(const std::string& file);

}  // namespace concert::discovery::dds
