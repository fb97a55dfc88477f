// Sensor files of the public database: concert_resources/sensors/<prefix>_sensors.yaml lists
// the sensors mounted on a module (e.g. mobile_platform_sensors.yaml: the CONCERT mobile
// platform's lidars, ultrasound sensors and cameras), with poses in the module's body frame.
// The JSON module files do not carry them, so they are attached here as sensor frames.

#include <yaml-cpp/yaml.h>

#include <algorithm>
#include <cmath>

#include "internal.hpp"

namespace concert::module_db::detail {
namespace {

namespace fs = std::filesystem;

Eigen::Matrix3d rpy_matrix(const Eigen::Vector3d& rpy) {
  return (Eigen::AngleAxisd(rpy[2], Eigen::Vector3d::UnitZ()) * Eigen::AngleAxisd(rpy[1], Eigen::Vector3d::UnitY()) *
          Eigen::AngleAxisd(rpy[0], Eigen::Vector3d::UnitX()))
      .toRotationMatrix();
}

Eigen::Vector3d vec3(const YAML::Node& node, const fs::path& file, const std::string& field) {
  if (!node || !node.IsSequence() || node.size() != 3) fail(file, field, "expected a list of 3 numbers");
  try {
    return {node[0].as<double>(), node[1].as<double>(), node[2].as<double>()};
  } catch (const YAML::Exception&) {
    fail(file, field, "expected a list of 3 numbers");
  }
}

}  // namespace

void attach_sensor_file(const fs::path& file, std::vector<ModuleDescription>& modules) {
  const std::string stem = file.stem().string();
  const std::string suffix = "_sensors";
  if (stem.size() <= suffix.size() || stem.compare(stem.size() - suffix.size(), suffix.size(), suffix) != 0) return;
  const std::string prefix = stem.substr(0, stem.size() - suffix.size());
  YAML::Node root;
  try {
    root = YAML::LoadFile(file.string());
  } catch (const YAML::Exception& e) {
    fail(file, "line " + std::to_string(e.mark.line + 1), e.msg);
  }
  if (!root["sensors"] || !root["sensors"].IsSequence()) fail(file, "sensors", "expected a list of sensors");
  std::vector<Frame> frames;
  const YAML::Node list = root["sensors"];
  for (std::size_t i = 0; i < list.size(); ++i) {
    const std::string field = "sensors[" + std::to_string(i) + "]";
    const YAML::Node s = list[i];
    if (!s["name"] || !s["type"]) fail(file, field, "expected name and type");
    const std::string type = s["type"].as<std::string>();
    Frame f;
    f.name = s["name"].as<std::string>();
    f.body = 0;
    Eigen::Matrix3d r = rpy_matrix(vec3(s["rpy"], file, field + ".rpy"));
    f.pose.translation() = vec3(s["xyz"], file, field + ".xyz");
    if (type == "lidar3d") {
      f.kind = FrameKind::kLidar;
    } else if (type == "sonar") {
      // The sensing axis is x after the mount and then `then_rpy` (as the file states).
      f.kind = FrameKind::kSonar;
      if (s["then_rpy"]) r = r * rpy_matrix(vec3(s["then_rpy"], file, field + ".then_rpy"));
    } else if (type == "rgbd") {
      // The file gives the camera's mount (x forward, z up); the sensor frame is optical.
      f.kind = FrameKind::kCamera;
      r = r * rpy_matrix({-M_PI / 2, 0.0, -M_PI / 2});
    } else {
      continue;  // tracking and plain RGB cameras are not sensor frames of the model (yet)
    }
    f.pose.linear() = r;
    frames.push_back(std::move(f));
  }
  for (ModuleDescription& m : modules) {
    if (m.key.rfind(prefix, 0) != 0) continue;
    for (const Frame& f : frames) {
      if (std::none_of(m.frames.begin(), m.frames.end(), [&](const Frame& g) { return g.name == f.name; })) {
        Frame g = f;
        g.body = m.root_body();
        m.frames.push_back(std::move(g));
      }
    }
  }
}

}  // namespace concert::module_db::detail
