#include "service_params.hpp"

namespace concert::discovery::dds {

ServiceParams read_service_params(config::Document& doc) {
  ServiceParams p;
  config::Map root = doc.root();
  root.strings("module_db", p.module_dbs, true);
  root.choice("port_order", p.port_order, {"0312", "0123"});
  doc.finish();
  return p;
}

ServiceParams load_service_params(const std::string& file) {
  return config::Document::load(file).read_with(read_service_params);
}

}  // namespace concert::discovery::dds
