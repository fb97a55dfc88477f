#include "safety/params.hpp"

namespace concert::safety {

Params read_params(config::Document& doc) {
  Params p;
  config::Map root = doc.root();
  const auto period = config::Range{0.0, 3600.0, true};
  root.duration("liveliness_timeout", p.liveliness_timeout, period);
  root.string("robot_service", p.robot_service, false);
  root.strings("task_services", p.task_services);
  root.boolean("require_robot", p.require_robot);
  root.number("position_tolerance", p.position_tolerance, config::Range::non_negative());
  root.number("velocity_margin", p.velocity_margin, config::Range::non_negative());
  root.number("effort_margin", p.effort_margin, config::Range::non_negative());
  root.duration("publish_period", p.publish_period, period);
  root.duration("check_period", p.check_period, period);
  root.integer("stall_checks", p.stall_checks, 0, 1000);
  root.integer("nice", p.nice, -20, 19);
  doc.finish();
  if (p.check_period > p.liveliness_timeout) {
    root.fail("check_period", "must not exceed liveliness_timeout");
  }
  return p;
}

Params parse_params(const std::string& yaml, const std::string& origin) {
  return config::Document::parse(yaml, origin).read_with(read_params);
}

Params load_params(const std::string& file) {
  return config::Document::load(file).read_with(read_params);
}

}  // namespace concert::safety
