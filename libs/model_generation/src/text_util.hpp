#pragma once
// Number and pose formatting shared by the writers: fixed, locale-independent, deterministic.

#include <cmath>
#include <cstdio>
#include <string>

#include <Eigen/Geometry>

namespace concert::model_generation::detail {

/// Shortest round-trip-safe enough text of a double (12 significant digits), never "-0".
inline std::string num(double v) {
  if (std::abs(v) < 1e-15) v = 0.0;
  char buf[40];
  std::snprintf(buf, sizeof buf, "%.12g", v);
  return buf;
}

inline std::string vec(const Eigen::Vector3d& v) { return num(v.x()) + " " + num(v.y()) + " " + num(v.z()); }

/// URDF roll-pitch-yaw of a rotation: R = Rz(yaw) * Ry(pitch) * Rx(roll).
inline Eigen::Vector3d rpy(const Eigen::Matrix3d& r) {
  const double pitch = std::atan2(-r(2, 0), std::hypot(r(0, 0), r(1, 0)));
  double roll = 0.0;
  double yaw = 0.0;
  if (std::hypot(r(0, 0), r(1, 0)) > 1e-9) {
    roll = std::atan2(r(2, 1), r(2, 2));
    yaw = std::atan2(r(1, 0), r(0, 0));
  } else {
    yaw = std::atan2(-r(0, 1), r(1, 1));
  }
  return {roll, pitch, yaw};
}

inline std::string origin(const Eigen::Isometry3d& p) {
  return "<origin xyz=\"" + vec(p.translation()) + "\" rpy=\"" + vec(rpy(p.linear())) + "\"/>";
}

inline std::string xml_escape(const std::string& s) {
  std::string out;
  for (char c : s) {
    switch (c) {
      case '&': out += "&amp;"; break;
      case '<': out += "&lt;"; break;
      case '>': out += "&gt;"; break;
      case '"': out += "&quot;"; break;
      default: out += c;
    }
  }
  return out;
}

}  // namespace concert::model_generation::detail
