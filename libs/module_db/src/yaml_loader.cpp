// Reader of the project's own YAML module database (schema: data/module_db/README.md).

#include <yaml-cpp/yaml.h>

#include <cmath>
#include <fstream>
#include <limits>
#include <sstream>

#include "concert/common/text.hpp"
#include "concert/module_db/module_db.hpp"
#include "internal.hpp"

namespace concert::module_db {
namespace {

using detail::fail;
namespace fs = std::filesystem;

std::string at_line(const YAML::Node& n) {
  const YAML::Mark mark = n.Mark();
  if (mark.line < 0) return "";
  return " (line " + std::to_string(mark.line + 1) + ")";
}

YAML::Node req(const YAML::Node& obj, const std::string& key, const fs::path& file, const std::string& path) {
  if (!obj.IsMap()) fail(file, path.empty() ? "(document)" : path.substr(0, path.size() - 1), "expected a mapping" + at_line(obj));
  YAML::Node v = obj[key];
  if (!v || v.IsNull()) fail(file, path + key, "missing" + at_line(obj));
  return v;
}

double num(const YAML::Node& v, const fs::path& file, const std::string& field) {
  if (v.IsScalar()) {
    const std::string s = v.Scalar();
    if (s == ".inf" || s == "inf") return std::numeric_limits<double>::infinity();
    if (s == "-.inf" || s == "-inf") return -std::numeric_limits<double>::infinity();
    try {
      size_t pos = 0;
      const double d = std::stod(s, &pos);
      if (pos == s.size()) return d;
    } catch (const std::exception&) {
    }
  }
  fail(file, field, "not a number" + at_line(v));
}

double req_num(const YAML::Node& obj, const std::string& key, const fs::path& file, const std::string& path) {
  return num(req(obj, key, file, path), file, path + key);
}

double opt_num(const YAML::Node& obj, const std::string& key, double fallback, const fs::path& file, const std::string& path) {
  if (!obj.IsMap() || !obj[key] || obj[key].IsNull()) return fallback;
  return num(obj[key], file, path + key);
}

std::string opt_str(const YAML::Node& obj, const std::string& key, const std::string& fallback = "") {
  if (!obj.IsMap() || !obj[key] || !obj[key].IsScalar()) return fallback;
  return obj[key].Scalar();
}

std::string req_str(const YAML::Node& obj, const std::string& key, const fs::path& file, const std::string& path) {
  const YAML::Node v = req(obj, key, file, path);
  if (!v.IsScalar()) fail(file, path + key, "expected a string" + at_line(v));
  return v.Scalar();
}

Eigen::Vector3d vec3(const YAML::Node& v, const fs::path& file, const std::string& field) {
  if (!v.IsSequence() || v.size() != 3) fail(file, field, "expected 3 numbers" + at_line(v));
  Eigen::Vector3d out;
  for (size_t i = 0; i < 3; ++i) out[static_cast<Eigen::Index>(i)] = num(v[i], file, field + "[" + std::to_string(i) + "]");
  return out;
}

/// URDF convention: R = Rz(yaw) * Ry(pitch) * Rx(roll), angles in rad.
Pose pose_xyz_rpy(const YAML::Node& v, const fs::path& file, const std::string& field) {
  if (!v || v.IsNull()) return Pose::Identity();
  if (!v.IsMap()) fail(file, field, "expected {xyz: [..], rpy: [..]}" + at_line(v));
  for (auto it = v.begin(); it != v.end(); ++it) {
    const std::string k = it->first.Scalar();
    if (k != "xyz" && k != "rpy") fail(file, field + "." + k, "unknown key (expected xyz, rpy)" + at_line(it->first));
  }
  Pose p = Pose::Identity();
  if (v["xyz"]) p.translation() = vec3(v["xyz"], file, field + ".xyz");
  if (v["rpy"]) {
    const Eigen::Vector3d rpy = vec3(v["rpy"], file, field + ".rpy");
    p.linear() = (Eigen::AngleAxisd(rpy[2], Eigen::Vector3d::UnitZ()) * Eigen::AngleAxisd(rpy[1], Eigen::Vector3d::UnitY()) *
                  Eigen::AngleAxisd(rpy[0], Eigen::Vector3d::UnitX()))
                     .toRotationMatrix();
  }
  return p;
}

std::vector<Shape> shapes(const YAML::Node& arr, const fs::path& file, const std::string& path) {
  std::vector<Shape> out;
  if (!arr || arr.IsNull()) return out;
  if (!arr.IsSequence()) fail(file, path, "expected a list" + at_line(arr));
  for (size_t i = 0; i < arr.size(); ++i) {
    const YAML::Node s = arr[i];
    const std::string p = path + "[" + std::to_string(i) + "].";
    if (!s.IsMap()) fail(file, p.substr(0, p.size() - 1), "expected a mapping" + at_line(s));
    Shape sh;
    if (s["mesh"]) {
      sh.kind = Shape::Kind::kMesh;
      sh.mesh = s["mesh"].Scalar();
      if (s["scale"]) sh.scale = vec3(s["scale"], file, p + "scale");
    } else if (s["box"]) {
      sh.kind = Shape::Kind::kBox;
      sh.size = vec3(s["box"], file, p + "box");
    } else if (s["cylinder"]) {
      sh.kind = Shape::Kind::kCylinder;
      sh.radius = req_num(s["cylinder"], "radius", file, p + "cylinder.");
      sh.length = req_num(s["cylinder"], "length", file, p + "cylinder.");
    } else if (s["sphere"]) {
      sh.kind = Shape::Kind::kSphere;
      sh.radius = req_num(s["sphere"], "radius", file, p + "sphere.");
    } else {
      fail(file, p.substr(0, p.size() - 1), "expected one of mesh, box, cylinder, sphere" + at_line(s));
    }
    sh.pose = pose_xyz_rpy(s["pose"], file, p + "pose");
    sh.material = opt_str(s, "material");
    if (s["rgba"]) {
      const YAML::Node c = s["rgba"];
      if (!c.IsSequence() || c.size() != 4) fail(file, p + "rgba", "expected 4 numbers" + at_line(c));
      Eigen::Vector4d rgba;
      for (size_t k = 0; k < 4; ++k) rgba[static_cast<Eigen::Index>(k)] = num(c[k], file, p + "rgba");
      sh.rgba = rgba;
    }
    out.push_back(std::move(sh));
  }
  return out;
}

ConnectorRole role_from(const std::string& r, const fs::path& file, const std::string& field) {
  if (r == "input") return ConnectorRole::kInput;
  if (r == "output") return ConnectorRole::kOutput;
  if (r == "tcp") return ConnectorRole::kTcp;
  if (r == "base") return ConnectorRole::kBase;
  fail(file, field, "unknown role '" + r + "' (expected input, output, tcp, base)");
}

/// `from_string(name)` (one of the module_db *_from_string functions), its std::invalid_argument
/// turned into an error naming the file and field.
template <class Enum>
Enum enum_from(Enum (*from_string)(const std::string&), const std::string& name, const fs::path& file,
               const std::string& field) {
  try {
    return from_string(name);
  } catch (const std::invalid_argument& e) {
    fail(file, field, e.what());
  }
}

std::vector<std::string> string_list(const YAML::Node& v, const fs::path& file, const std::string& field) {
  std::vector<std::string> out;
  if (!v || v.IsNull()) return out;
  if (!v.IsSequence()) fail(file, field, "expected a list" + at_line(v));
  for (const YAML::Node& s : v) out.push_back(s.Scalar());
  return out;
}

YAML::Node load_file(const fs::path& file) {
  std::ifstream in(file, std::ios::binary);
  if (!in || fs::is_directory(file)) throw ModuleDbError(file.string() + ": cannot open");
  std::ostringstream text;
  text << in.rdbuf();
  // yaml-cpp takes bytes that are not UTF-8 as they come: they would reach the generated URDF,
  // which the services refuse (a tests/fuzz regression).
  if (const auto at = invalid_utf8_at(text.str())) {
    fail(file, "(document)", "not valid UTF-8 (byte " + std::to_string(*at) + ")");
  }
  try {
    return YAML::Load(text.str());
  } catch (const YAML::Exception& e) {
    fail(file, "(document)", std::string("invalid YAML: ") + e.what());
  }
}

/// The document of a module or add-on file, which must be a mapping; sets what both share: the key
/// (default: the file name), the source file and the label (default: the key).
template <class Description>
YAML::Node read_document(const fs::path& file, Description& d) {
  YAML::Node doc = load_file(file);
  if (!doc.IsMap()) fail(file, "(document)", "expected a mapping");
  d.key = opt_str(doc, "key", file.stem().string());
  d.source = file.string();
  d.label = opt_str(doc, "label", d.key);
  return doc;
}

/// Calls `read(item, prefix)` for every item of the document-level list `field`, with the field
/// prefix of the item ("joints[2].").
template <class Read>
void for_each_item(const YAML::Node& list, const fs::path& file, const std::string& field,
                   Read read) {
  if (!list.IsSequence()) fail(file, field, "expected a list");
  for (size_t i = 0; i < list.size(); ++i) read(list[i], field + "[" + std::to_string(i) + "].");
}

ModuleDescription read_module(const fs::path& file) {
  ModuleDescription m;
  const YAML::Node doc = read_document(file, m);
  m.type = enum_from(module_type_from_string, req_str(doc, "type", file, ""), file, "type");
  m.tags = string_list(doc["tags"], file, "tags");
  m.addon_types = string_list(doc["addon_types"], file, "addon_types");
  if (doc["actuator"]) {
    ModuleDescription::Actuator a;
    a.name = req_str(doc["actuator"], "name", file, "actuator.");
    a.mass = req_num(doc["actuator"], "mass", file, "actuator.");
    m.actuator = a;
  }
  const YAML::Node bodies = req(doc, "bodies", file, "");
  if (!bodies.IsSequence() || bodies.size() == 0) fail(file, "bodies", "expected a non-empty list");
  std::map<std::string, int> body_index;
  for_each_item(bodies, file, "bodies", [&](const YAML::Node& b, const std::string& p) {
    Body body;
    body.name = req_str(b, "name", file, p);
    body.inertial.mass = req_num(b, "mass", file, p);
    body.inertial.com = vec3(req(b, "com", file, p), file, p + "com");
    const YAML::Node in = req(b, "inertia", file, p);
    if (!in.IsSequence() || in.size() != 6) fail(file, p + "inertia", "expected [ixx, iyy, izz, ixy, ixz, iyz]" + at_line(in));
    double v[6];
    for (size_t k = 0; k < 6; ++k) v[k] = num(in[k], file, p + "inertia[" + std::to_string(k) + "]");
    body.inertial.inertia << v[0], v[3], v[4], v[3], v[1], v[5], v[4], v[5], v[2];
    body.visuals = shapes(b["visual"], file, p + "visual");
    body.collisions = shapes(b["collision"], file, p + "collision");
    if (body_index.count(body.name)) fail(file, p + "name", "duplicate body name '" + body.name + "'");
    body_index[body.name] = static_cast<int>(m.bodies.size());
    m.bodies.push_back(std::move(body));
  });
  auto body_ref = [&](const YAML::Node& obj, const std::string& key, const std::string& p) {
    const std::string name = req_str(obj, key, file, p);
    auto it = body_index.find(name);
    if (it == body_index.end()) fail(file, p + key, "no body '" + name + "'");
    return it->second;
  };
  const YAML::Node connectors = req(doc, "connectors", file, "");
  for_each_item(connectors, file, "connectors", [&](const YAML::Node& c, const std::string& p) {
    Connector con;
    con.name = req_str(c, "name", file, p);
    con.role = role_from(req_str(c, "role", file, p), file, p + "role");
    con.body = body_ref(c, "body", p);
    con.type = opt_str(c, "type", "clamp");
    con.size = opt_str(c, "size");
    con.pose = pose_xyz_rpy(c["pose"], file, p + "pose");
    m.connectors.push_back(std::move(con));
  });
  if (doc["joints"]) {
    for_each_item(doc["joints"], file, "joints", [&](const YAML::Node& j, const std::string& p) {
      JointDescription jd;
      jd.name = req_str(j, "name", file, p);
      jd.parent_body = body_ref(j, "parent", p);
      jd.child_body = body_ref(j, "child", p);
      jd.type = enum_from(joint_type_from_string, req_str(j, "type", file, p), file, p + "type");
      jd.pose_parent = pose_xyz_rpy(j["pose_parent"], file, p + "pose_parent");
      jd.pose_child = pose_xyz_rpy(j["pose_child"], file, p + "pose_child");
      if (j["axis"]) jd.axis = vec3(j["axis"], file, p + "axis");
      if (jd.actuated()) {
        const YAML::Node lim = req(j, "limits", file, p);
        const std::string lp = p + "limits.";
        const double inf = std::numeric_limits<double>::infinity();
        if (jd.type == JointType::kContinuous) {
          jd.limits.lower = opt_num(lim, "lower", -inf, file, lp);
          jd.limits.upper = opt_num(lim, "upper", inf, file, lp);
        } else {
          jd.limits.lower = req_num(lim, "lower", file, lp);
          jd.limits.upper = req_num(lim, "upper", file, lp);
        }
        jd.limits.velocity = req_num(lim, "velocity", file, lp);
        jd.limits.peak_torque = req_num(lim, "peak_torque", file, lp);
        if (lim["continuous_torque"]) jd.limits.continuous_torque = req_num(lim, "continuous_torque", file, lp);
        jd.gear_ratio = req_num(j, "gear_ratio", file, p);
        jd.motor_inertia = opt_num(j, "motor_inertia", 0.0, file, p);
        jd.friction_viscous = opt_num(j, "friction_viscous", 0.0, file, p);
        if (j["control"]) {
          const YAML::Node c = j["control"];
          const std::string cp = p + "control.";
          jd.control.mode = opt_str(c, "mode");
          if (!jd.control.mode.empty() && jd.control.mode != "position" && jd.control.mode != "velocity" &&
              jd.control.mode != "impedance") {
            fail(file, cp + "mode", "unknown control mode '" + jd.control.mode + "' (expected position, velocity, impedance)");
          }
          jd.control.stiffness = opt_num(c, "stiffness", 0.0, file, cp);
          jd.control.damping = opt_num(c, "damping", 0.0, file, cp);
          jd.control.kp = opt_num(c, "kp", 0.0, file, cp);
          jd.control.ki = opt_num(c, "ki", 0.0, file, cp);
          jd.control.kd = opt_num(c, "kd", 0.0, file, cp);
        }
      }
      m.joints.push_back(std::move(jd));
    });
  }
  if (doc["frames"]) {
    for_each_item(doc["frames"], file, "frames", [&](const YAML::Node& f, const std::string& p) {
      Frame fr;
      fr.name = req_str(f, "name", file, p);
      fr.kind = enum_from(detail::frame_kind_from_string, req_str(f, "kind", file, p), file, p + "kind");
      fr.body = body_ref(f, "body", p);
      fr.pose = pose_xyz_rpy(f["pose"], file, p + "pose");
      m.frames.push_back(std::move(fr));
    });
  }
  detail::validate_and_normalise(m, file);
  return m;
}

AddonDescription read_addon(const fs::path& file) {
  AddonDescription a;
  const YAML::Node doc = read_document(file, a);
  a.type = req_str(doc, "type", file, "");
  a.mass = req_num(doc, "mass", file, "");
  if (a.mass < 0.0) fail(file, "mass", "must be >= 0");
  if (doc["com"]) a.com = vec3(doc["com"], file, "com");
  a.tcp_offset = opt_num(doc, "tcp_offset", 0.0, file, "");
  if (doc["frame"]) {
    const YAML::Node f = doc["frame"];
    Frame fr;
    fr.name = req_str(f, "name", file, "frame.");
    fr.kind = enum_from(detail::frame_kind_from_string, req_str(f, "kind", file, "frame."), file, "frame.kind");
    fr.pose = pose_xyz_rpy(f["pose"], file, "frame.pose");
    a.frame = fr;
  }
  if (doc["parameters"] && doc["parameters"].IsMap()) {
    for (auto it = doc["parameters"].begin(); it != doc["parameters"].end(); ++it) {
      a.parameters[it->first.Scalar()] = num(it->second, file, "parameters." + it->first.Scalar());
    }
  }
  return a;
}

/// `read()`, with an error of yaml-cpp that the reader does not check for (a node of another
/// kind than expected somewhere) turned into a ModuleDbError naming the file and the line.
template <class Read>
auto with_yaml_errors(const fs::path& file, Read read) {
  try {
    return read();
  } catch (const YAML::Exception& e) {
    fail(file, "(document)", "line " + std::to_string(e.mark.line + 1) + ": " + e.msg);
  }
}

}  // namespace

ModuleDescription load_yaml_module(const fs::path& file) {
  return with_yaml_errors(file, [&] { return read_module(file); });
}

AddonDescription load_yaml_addon(const fs::path& file) {
  return with_yaml_errors(file, [&] { return read_addon(file); });
}

}  // namespace concert::module_db
