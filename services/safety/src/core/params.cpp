#include "safety/params.hpp"

#include <yaml-cpp/yaml.h>

#include <cmath>
#include <fstream>
#include <set>
#include <sstream>
#include <stdexcept>

namespace concert::safety {
namespace {

std::runtime_error field_error(const std::string& origin, const std::string& field,
                               const std::string& what) {
  return std::runtime_error(origin + ": " + field + ": " + what);
}

double number(const YAML::Node& node, const std::string& origin, const std::string& field) {
  if (!node.IsScalar()) throw field_error(origin, field, "expected a number");
  try {
    const double v = node.as<double>();
    if (!std::isfinite(v)) throw field_error(origin, field, "expected a finite number");
    return v;
  } catch (const YAML::Exception&) {
    throw field_error(origin, field, "'" + node.Scalar() + "' is not a number");
  }
}

double non_negative(const YAML::Node& node, const std::string& origin, const std::string& field) {
  const double v = number(node, origin, field);
  if (v < 0.0) throw field_error(origin, field, "must not be negative (got " + node.Scalar() + ")");
  return v;
}

/// A period in seconds in the file, milliseconds in Params; must be > 0.
std::chrono::milliseconds period(const YAML::Node& node, const std::string& origin,
                                 const std::string& field) {
  const double s = number(node, origin, field);
  if (s <= 0.0 || s > 3600.0) {
    throw field_error(origin, field,
                      "expected a period in seconds in (0, 3600] (got " + node.Scalar() + ")");
  }
  const auto ms = std::chrono::milliseconds(static_cast<int64_t>(std::llround(s * 1000.0)));
  if (ms.count() == 0) throw field_error(origin, field, "must be at least 0.001 s");
  return ms;
}

std::string name(const YAML::Node& node, const std::string& origin, const std::string& field) {
  if (!node.IsScalar() || node.Scalar().empty())
    throw field_error(origin, field, "expected a service name");
  return node.Scalar();
}

}  // namespace

Params parse_params(const std::string& yaml, const std::string& origin) {
  YAML::Node root;
  try {
    root = YAML::Load(yaml);
  } catch (const YAML::Exception& e) {
    throw std::runtime_error(origin + ": invalid YAML: " + e.what());
  }
  Params p;
  if (root.IsNull()) return p;
  if (!root.IsMap()) throw std::runtime_error(origin + ": expected a mapping of safety parameters");
  static const std::set<std::string> kKeys = {
      "liveliness_timeout", "robot_service",      "task_services",
      "require_robot",      "position_tolerance", "velocity_margin",
      "effort_margin",      "publish_period",     "check_period"};
  for (const auto& entry : root) {
    const auto key = entry.first.Scalar();
    if (!kKeys.count(key)) throw field_error(origin, key, "unknown key");
    const YAML::Node& v = entry.second;
    if (key == "liveliness_timeout") {
      p.liveliness_timeout = period(v, origin, key);
    } else if (key == "robot_service") {
      p.robot_service = name(v, origin, key);
    } else if (key == "task_services") {
      if (!v.IsSequence()) throw field_error(origin, key, "expected a list of service names");
      p.task_services.clear();
      for (std::size_t i = 0; i < v.size(); ++i) {
        p.task_services.push_back(name(v[i], origin, key + "[" + std::to_string(i) + "]"));
      }
    } else if (key == "require_robot") {
      if (!v.IsScalar()) throw field_error(origin, key, "expected true or false");
      try {
        p.require_robot = v.as<bool>();
      } catch (const YAML::Exception&) {
        throw field_error(origin, key, "'" + v.Scalar() + "' is not true or false");
      }
    } else if (key == "position_tolerance") {
      p.position_tolerance = non_negative(v, origin, key);
    } else if (key == "velocity_margin") {
      p.velocity_margin = non_negative(v, origin, key);
    } else if (key == "effort_margin") {
      p.effort_margin = non_negative(v, origin, key);
    } else if (key == "publish_period") {
      p.publish_period = period(v, origin, key);
    } else if (key == "check_period") {
      p.check_period = period(v, origin, key);
    }
  }
  if (p.check_period > p.liveliness_timeout) {
    throw field_error(origin, "check_period", "must not exceed liveliness_timeout");
  }
  return p;
}

Params load_params(const std::string& file) {
  std::ifstream in(file);
  if (!in) throw std::runtime_error(file + ": cannot read the safety parameters file");
  std::stringstream text;
  text << in.rdbuf();
  return parse_params(text.str(), file);
}

}  // namespace concert::safety
