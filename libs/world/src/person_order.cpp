#include "concert/world/person_order.hpp"

#include <yaml-cpp/yaml.h>

#include <cmath>
#include <sstream>
#include <stdexcept>

#include "concert/config/config.hpp"

namespace concert::world {

namespace {

using config::Map;
using config::Range;

PersonOrder read_order(config::Document& doc, bool& status) {
  PersonOrder o;
  Map root = doc.root();
  std::string action;
  root.choice("action", action, {"grip", "walk", "release", "status"});
  if (action.empty()) root.fail("action", "expected one of grip, walk, release, status");
  status = action == "status";
  o.action = action == "walk" ? PersonOrder::Action::kWalk
             : action == "release" ? PersonOrder::Action::kRelease
                                   : PersonOrder::Action::kGrip;
  if (action == "grip") {
    root.string("link", o.link);
    std::vector<double> guide;
    root.numbers("guide", guide, 3);
    if (!guide.empty()) o.guide = Eigen::Vector3d(guide[0], guide[1], guide[2]);
    root.number("guide_time", o.guide_time, Range::non_negative());
    PersonParams& p = o.params;
    root.number("stiffness", p.stiffness, Range::positive());
    root.number("damping", p.damping, Range::non_negative());
    root.number("speed", p.speed, Range::positive());
    root.number("ramp", p.ramp, Range::non_negative());
    root.number("wait_stretch", p.wait_stretch, Range::positive());
    root.number("let_go_stretch", p.let_go_stretch, Range::positive());
    root.number("arrive_radius", p.arrive_radius, Range::positive());
    root.number("arrive_time", p.arrive_time, Range::non_negative());
    if (p.wait_stretch >= p.let_go_stretch) {
      std::ostringstream what;
      what << "expected below let_go_stretch (" << p.let_go_stretch << "): the person waits before letting go";
      root.fail("wait_stretch", what.str());
    }
  } else if (action == "walk") {
    std::vector<double> route;
    root.numbers("route", route);
    if (route.empty() || route.size() % 2 != 0)
      root.fail("route", "expected x, y pairs [m], at least one (got " + std::to_string(route.size()) + " numbers)");
    for (std::size_t i = 0; i + 1 < route.size(); i += 2) o.route.emplace_back(route[i], route[i + 1]);
    root.boolean("relative", o.relative);
  }
  doc.finish();
  return o;
}

}  // namespace

std::optional<PersonOrder> parse_person_order(const std::string& yaml, const std::string& source) {
  try {
    bool status = false;
    config::Document doc = config::Document::parse(yaml, source);
    PersonOrder o = read_order(doc, status);
    if (status) return std::nullopt;
    return o;
  } catch (const config::ConfigError& e) {
    throw std::invalid_argument(e.what());
  }
}

std::string person_order_yaml(const PersonOrder& o) {
  YAML::Emitter out;
  out << YAML::BeginMap;
  switch (o.action) {
    case PersonOrder::Action::kGrip: {
      out << YAML::Key << "action" << YAML::Value << "grip";
      if (!o.link.empty()) out << YAML::Key << "link" << YAML::Value << o.link;
      out << YAML::Key << "guide" << YAML::Value << YAML::Flow << YAML::BeginSeq << o.guide.x() << o.guide.y()
          << o.guide.z() << YAML::EndSeq;
      out << YAML::Key << "guide_time" << YAML::Value << o.guide_time;
      const PersonParams& p = o.params;
      out << YAML::Key << "stiffness" << YAML::Value << p.stiffness << YAML::Key << "damping" << YAML::Value
          << p.damping << YAML::Key << "speed" << YAML::Value << p.speed << YAML::Key << "ramp" << YAML::Value
          << p.ramp << YAML::Key << "wait_stretch" << YAML::Value << p.wait_stretch << YAML::Key
          << "let_go_stretch" << YAML::Value << p.let_go_stretch << YAML::Key << "arrive_radius" << YAML::Value
          << p.arrive_radius << YAML::Key << "arrive_time" << YAML::Value << p.arrive_time;
      break;
    }
    case PersonOrder::Action::kWalk:
      out << YAML::Key << "action" << YAML::Value << "walk";
      out << YAML::Key << "route" << YAML::Value << YAML::Flow << YAML::BeginSeq;
      for (const Eigen::Vector2d& p : o.route) out << p.x() << p.y();
      out << YAML::EndSeq;
      out << YAML::Key << "relative" << YAML::Value << o.relative;
      break;
    case PersonOrder::Action::kRelease:
      out << YAML::Key << "action" << YAML::Value << "release";
      break;
  }
  out << YAML::EndMap;
  return std::string(out.c_str()) + "\n";
}

std::string person_report_yaml(const PersonReport& r) {
  YAML::Emitter out;
  out.SetFloatPrecision(6);
  out.SetDoublePrecision(6);
  const auto vec = [&](const char* key, const Eigen::Vector3d& v) {
    out << YAML::Key << key << YAML::Value << YAML::Flow << YAML::BeginSeq << v.x() << v.y() << v.z() << YAML::EndSeq;
  };
  out << YAML::Flow << YAML::BeginMap;
  out << YAML::Key << "phase" << YAML::Value << YAML::DoubleQuoted << to_string(r.phase);
  out << YAML::Key << "link" << YAML::Value << YAML::DoubleQuoted << r.link;
  out << YAML::Key << "reason" << YAML::Value << YAML::DoubleQuoted << r.reason;
  out << YAML::Key << "walked" << YAML::Value << r.walked;
  out << YAML::Key << "route_length" << YAML::Value << r.route_length;
  out << YAML::Key << "pull" << YAML::Value << r.pull.norm();
  out << YAML::Key << "peak_pull" << YAML::Value << r.peak_pull;
  vec("hand", r.hand);
  vec("tcp", r.tcp);
  vec("pull_vector", r.pull);
  out << YAML::Key << "time" << YAML::Value << r.time;
  out << YAML::Key << "orders" << YAML::Value << r.orders;
  out << YAML::EndMap;
  return out.c_str();
}

PersonPhase person_phase(const std::string& name) {
  for (PersonPhase p : {PersonPhase::kAbsent, PersonPhase::kGuiding, PersonPhase::kHolding, PersonPhase::kWalking,
                        PersonPhase::kWaiting, PersonPhase::kArrived, PersonPhase::kLetGo}) {
    if (name == to_string(p)) return p;
  }
  throw std::invalid_argument("person: no phase '" + name +
                              "' (absent, guiding, holding, walking, waiting, arrived, let go)");
}

PersonReport parse_person_report(const std::string& yaml) {
  try {
    const YAML::Node n = YAML::Load(yaml);
    PersonReport r;
    r.phase = person_phase(n["phase"].as<std::string>());
    r.link = n["link"].as<std::string>();
    r.reason = n["reason"].as<std::string>();
    r.walked = n["walked"].as<double>();
    r.route_length = n["route_length"].as<double>();
    r.peak_pull = n["peak_pull"].as<double>();
    const auto vec = [&](const char* key) {
      const YAML::Node v = n[key];
      return Eigen::Vector3d(v[0].as<double>(), v[1].as<double>(), v[2].as<double>());
    };
    r.hand = vec("hand");
    r.tcp = vec("tcp");
    r.pull = vec("pull_vector");
    r.time = n["time"].as<double>();
    r.orders = n["orders"].as<std::uint64_t>();
    return r;
  } catch (const YAML::Exception& e) {
    throw std::invalid_argument(std::string("person report: ") + e.what());
  }
}

}  // namespace concert::world
