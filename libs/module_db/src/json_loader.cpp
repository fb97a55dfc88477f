// Reader of the public CONCERT module database (CoBRA/Timor JSON: header, bodies, joints,
// connectors; add-ons in module_addons/json/).

#include <cmath>
#include <fstream>
#include <limits>
#include <sstream>

#include <nlohmann/json.hpp>

#include "concert/module_db/module_db.hpp"
#include "internal.hpp"

namespace concert::module_db {
namespace {

using nlohmann::json;
using detail::fail;
namespace fs = std::filesystem;

/// The public files use Python's json extension `Infinity` (e.g.
/// mobile_platform_concert_timor_planar.json), which nlohmann::json rejects; outside strings it
/// becomes 1e308, i.e. unbounded.
std::string replace_infinity(const std::string& text) {
  std::string out;
  out.reserve(text.size());
  bool in_string = false;
  for (size_t i = 0; i < text.size(); ++i) {
    const char c = text[i];
    if (in_string) {
      out += c;
      if (c == '\\' && i + 1 < text.size()) {
        out += text[++i];
      } else if (c == '"') {
        in_string = false;
      }
      continue;
    }
    if (c == '"') in_string = true;
    if (text.compare(i, 8, "Infinity") == 0) {
      out += "1e308";
      i += 7;
      continue;
    }
    out += c;
  }
  return out;
}

json read_json(const fs::path& file) {
  std::ifstream in(file);
  if (!in) throw ModuleDbError(file.string() + ": cannot open");
  std::stringstream ss;
  ss << in.rdbuf();
  try {
    return json::parse(replace_infinity(ss.str()));
  } catch (const json::exception& e) {  // not JSON, or a number out of range (out_of_range)
    fail(file, "(document)", std::string("invalid JSON: ") + e.what());
  }
}

const json& req(const json& obj, const std::string& key, const fs::path& file, const std::string& path) {
  if (!obj.is_object() || !obj.contains(key) || obj.at(key).is_null()) fail(file, path + key, "missing");
  return obj.at(key);
}

double num(const json& v, const fs::path& file, const std::string& field) {
  if (v.is_number()) return v.get<double>();
  if (v.is_string()) {
    try {
      size_t pos = 0;
      const std::string s = v.get<std::string>();
      double d = std::stod(s, &pos);
      if (pos == s.size()) return d;
    } catch (const std::exception&) {
    }
  }
  fail(file, field, "not a number");
}

double req_num(const json& obj, const std::string& key, const fs::path& file, const std::string& path) {
  return num(req(obj, key, file, path), file, path + key);
}

std::string str(const json& obj, const std::string& key, const std::string& fallback = "") {
  if (obj.is_object() && obj.contains(key) && obj.at(key).is_string()) return obj.at(key).get<std::string>();
  return fallback;
}

bool boolean(const json& obj, const std::string& key, bool fallback) {
  if (!obj.is_object() || !obj.contains(key)) return fallback;
  const json& v = obj.at(key);
  if (v.is_boolean()) return v.get<bool>();
  if (v.is_string()) return v.get<std::string>() == "true" || v.get<std::string>() == "True";
  return fallback;
}

Eigen::Vector3d vec3(const json& v, const fs::path& file, const std::string& field) {
  if (!v.is_array() || v.size() != 3) fail(file, field, "expected 3 numbers");
  Eigen::Vector3d out;
  for (Eigen::Index i = 0; i < 3; ++i) out[i] = num(v[static_cast<size_t>(i)], file, field + "[" + std::to_string(i) + "]");
  return out;
}

Pose pose4(const json& v, const fs::path& file, const std::string& field) {
  if (!v.is_array() || (v.size() != 4 && v.size() != 3)) fail(file, field, "expected a 4x4 matrix");
  Eigen::Matrix4d m = Eigen::Matrix4d::Identity();
  for (size_t r = 0; r < v.size(); ++r) {
    if (!v[r].is_array() || v[r].size() != 4) fail(file, field + "[" + std::to_string(r) + "]", "expected 4 numbers");
    for (size_t c = 0; c < 4; ++c) {
      m(static_cast<Eigen::Index>(r), static_cast<Eigen::Index>(c)) =
          num(v[r][c], file, field + "[" + std::to_string(r) + "][" + std::to_string(c) + "]");
    }
  }
  Pose p = Pose::Identity();
  p.matrix() = m;
  return p;
}

Pose opt_pose(const json& obj, const fs::path& file, const std::string& path) {
  if (obj.is_object() && obj.contains("pose") && !obj.at("pose").is_null()) return pose4(obj.at("pose"), file, path + "pose");
  return Pose::Identity();
}

std::vector<Shape> shapes(const json& arr, const fs::path& file, const std::string& path) {
  std::vector<Shape> out;
  if (arr.is_null()) return out;
  if (!arr.is_array()) fail(file, path, "expected a list");
  for (size_t i = 0; i < arr.size(); ++i) {
    const json& s = arr[i];
    const std::string p = path + "[" + std::to_string(i) + "].";
    Shape sh;
    const std::string type = str(s, "type");
    const json params = s.contains("parameters") ? s.at("parameters") : json::object();
    if (type == "mesh") {
      sh.kind = Shape::Kind::kMesh;
      sh.mesh = str(params, "file");
      if (sh.mesh.empty()) fail(file, p + "parameters.file", "missing");
      if (params.contains("scale")) sh.scale = vec3(params.at("scale"), file, p + "parameters.scale");
    } else if (type == "cylinder") {
      sh.kind = Shape::Kind::kCylinder;
      sh.radius = req_num(params, "radius", file, p + "parameters.");
      sh.length = req_num(params, "length", file, p + "parameters.");
    } else if (type == "sphere") {
      sh.kind = Shape::Kind::kSphere;
      sh.radius = req_num(params, "radius", file, p + "parameters.");
    } else if (type == "box") {
      sh.kind = Shape::Kind::kBox;
      if (params.contains("size")) {
        sh.size = vec3(params.at("size"), file, p + "parameters.size");
      } else {
        sh.size = Eigen::Vector3d(req_num(params, "x", file, p + "parameters."), req_num(params, "y", file, p + "parameters."),
                                  req_num(params, "z", file, p + "parameters."));
      }
    } else {
      fail(file, p + "type", "unknown shape type '" + type + "'");
    }
    if (params.contains("color") && params.at("color").is_object()) {
      const json& c = params.at("color");
      sh.material = str(c, "material_name");
      if (c.contains("rgba") && c.at("rgba").is_array() && c.at("rgba").size() == 4) {
        Eigen::Vector4d rgba;
        for (size_t k = 0; k < 4; ++k) rgba[static_cast<Eigen::Index>(k)] = num(c.at("rgba")[k], file, p + "parameters.color.rgba");
        sh.rgba = rgba;
      }
    }
    sh.pose = opt_pose(s, file, p);
    out.push_back(std::move(sh));
  }
  return out;
}

ModuleType type_from_header(const std::string& t, const fs::path& file) {
  if (t == "joint") return ModuleType::kJoint;
  if (t == "mobile_base") return ModuleType::kMobileBase;
  if (t == "cube" || t == "hub") return ModuleType::kHub;
  if (t == "link" || t == "interface_adapter" || t == "passive_link") return ModuleType::kLink;
  if (t == "base_link") return ModuleType::kBaseLink;
  if (t == "wheel") return ModuleType::kWheel;
  if (t == "end_effector" || t == "drill" || t == "spraying_tool" || t == "sanding_tool" || t == "gripper" ||
      t == "tool") {
    return ModuleType::kEndEffector;
  }
  fail(file, "header.type", "unknown module type '" + t + "'");
}

std::string control_mode_from_xbot(const std::string& m) {
  if (m.find("vel") != std::string::npos) return "velocity";
  if (m.find("imp") != std::string::npos) return "impedance";
  if (m.find("pos") != std::string::npos) return "position";
  return "";
}

/// The `header` object of a module or add-on file; sets what both share: the key (the file name),
/// the source file and the label (default: the key).
template <class Description>
const json& read_header(const json& doc, const fs::path& file, Description& d) {
  d.key = file.stem().string();
  d.source = file.string();
  const json& header = req(doc, "header", file, "");
  d.label = str(header, "label", d.key);
  return header;
}

/// Calls `read(item, prefix)` for every item of the list at `field`, with the field prefix of the
/// item ("joints[2].").
template <class Read>
void for_each_item(const json& list, const fs::path& file, const std::string& field, Read read) {
  if (!list.is_array()) fail(file, field, "expected a list");
  for (size_t i = 0; i < list.size(); ++i) read(list[i], field + "[" + std::to_string(i) + "].");
}

}  // namespace

ModuleDescription load_json_module(const fs::path& file) {
  const json doc = read_json(file);
  ModuleDescription m;
  const json& header = read_header(doc, file, m);
  const std::string htype = str(header, "type");
  if (htype.empty()) fail(file, "header.type", "missing");
  m.type = type_from_header(htype, file);
  m.tags.push_back(htype);
  if (header.contains("addons") && header.at("addons").is_array()) {
    for (const json& a : header.at("addons")) {
      if (a.is_string()) m.addon_types.push_back(a.get<std::string>());
    }
  }
  const json& bodies = req(doc, "bodies", file, "");
  if (!bodies.is_array() || bodies.empty()) fail(file, "bodies", "expected a non-empty list");
  std::map<std::string, int> body_index;
  for_each_item(bodies, file, "bodies", [&](const json& b, const std::string& p) {
    const int index = static_cast<int>(m.bodies.size());
    Body body;
    const json& id = req(b, "ID", file, p);
    body.name = id.is_string() ? id.get<std::string>() : id.dump();
    body.inertial.mass = req_num(b, "mass", file, p);
    body.inertial.com = vec3(req(b, "r_com", file, p), file, p + "r_com");
    const json& inertia = req(b, "inertia", file, p);
    if (!inertia.is_array() || inertia.size() != 3) fail(file, p + "inertia", "expected a 3x3 matrix");
    for (size_t r = 0; r < 3; ++r) {
      const Eigen::Vector3d row = vec3(inertia[r], file, p + "inertia[" + std::to_string(r) + "]");
      body.inertial.inertia.row(static_cast<Eigen::Index>(r)) = row.transpose();
    }
    body.visuals = shapes(b.value("visual", json()), file, p + "visual");
    body.collisions = shapes(b.value("collision", json()), file, p + "collision");
    body_index[body.name] = index;
    if (b.contains("connectors")) {
      for_each_item(b.at("connectors"), file, p + "connectors", [&](const json& c, const std::string& cp) {
        Connector con;
        const json& cid = req(c, "ID", file, cp);
        con.name = cid.is_string() ? cid.get<std::string>() : cid.dump();
        con.body = index;
        con.pose = pose4(req(c, "pose", file, cp), file, cp + "pose");
        con.type = str(c, "type");
        con.size = str(c, "size");
        const std::string gender = str(c, "gender");
        if (gender.empty()) fail(file, cp + "gender", "missing");
        if (con.type == "eef" || gender == "e") {
          con.role = ConnectorRole::kTcp;
        } else if (con.type == "base") {
          con.role = ConnectorRole::kBase;
        } else if (gender == "f") {
          con.role = ConnectorRole::kInput;
        } else if (gender == "m") {
          con.role = ConnectorRole::kOutput;
        } else {
          fail(file, cp + "gender", "unknown gender '" + gender + "'");
        }
        m.connectors.push_back(std::move(con));
      });
    }
    m.bodies.push_back(std::move(body));
  });
  if (doc.contains("joints")) {
    for_each_item(doc.at("joints"), file, "joints", [&](const json& j, const std::string& p) {
      JointDescription jd;
      const json& jid = req(j, "ID", file, p);
      jd.name = jid.is_string() ? jid.get<std::string>() : jid.dump();
      const json& pj = req(j, "parent", file, p);
      const json& cj = req(j, "child", file, p);
      if (!pj.is_string()) fail(file, p + "parent", "expected a body ID string");
      if (!cj.is_string()) fail(file, p + "child", "expected a body ID string");
      const std::string parent = pj.get<std::string>();
      const std::string child = cj.get<std::string>();
      if (!body_index.count(parent)) fail(file, p + "parent", "no body '" + parent + "'");
      if (!body_index.count(child)) fail(file, p + "child", "no body '" + child + "'");
      jd.parent_body = body_index.at(parent);
      jd.child_body = body_index.at(child);
      const std::string type = str(j, "type");
      if (type.empty()) fail(file, p + "type", "missing");
      jd.pose_parent = pose4(req(j, "pose_parent", file, p), file, p + "pose_parent");
      jd.pose_child = pose4(req(j, "pose_child", file, p), file, p + "pose_child");
      if (type == "fixed") {
        jd.type = JointType::kFixed;
      } else if (type == "revolute" || type == "prismatic" || type == "continuous") {
        jd.type = type == "prismatic" ? JointType::kPrismatic : JointType::kRevolute;
        const json& lim = req(j, "limits", file, p);
        const std::string lp = p + "limits.";
        const double inf = std::numeric_limits<double>::infinity();
        jd.limits.lower = lim.contains("positionLower") ? num(lim.at("positionLower"), file, lp + "positionLower") : -inf;
        jd.limits.upper = lim.contains("positionUpper") ? num(lim.at("positionUpper"), file, lp + "positionUpper") : inf;
        jd.limits.velocity = req_num(lim, "velocity", file, lp);
        if (lim.contains("peak_torque")) {
          jd.limits.peak_torque = num(lim.at("peak_torque"), file, lp + "peak_torque");
        } else {
          jd.limits.peak_torque = req_num(lim, "peakTorque", file, lp);
        }
        if (lim.contains("continuous_torque") && !lim.at("continuous_torque").is_null()) {
          jd.limits.continuous_torque = num(lim.at("continuous_torque"), file, lp + "continuous_torque");
        }
        if (type == "continuous" || (jd.type == JointType::kRevolute && jd.limits.upper >= detail::kUnboundedLimit &&
                                     jd.limits.lower <= -detail::kUnboundedLimit)) {
          jd.type = JointType::kContinuous;
        }
        if (j.contains("gear_ratio") && !j.at("gear_ratio").is_null()) jd.gear_ratio = num(j.at("gear_ratio"), file, p + "gear_ratio");
        if (j.contains("motor_inertia") && !j.at("motor_inertia").is_null()) {
          jd.motor_inertia = num(j.at("motor_inertia"), file, p + "motor_inertia");
        }
        if (j.contains("friction_viscous") && !j.at("friction_viscous").is_null()) {
          jd.friction_viscous = num(j.at("friction_viscous"), file, p + "friction_viscous");
        }
        if (boolean(j, "passive", false)) jd.type = JointType::kFixed;
        const json xbot = j.contains("control_parameters") && j.at("control_parameters").contains("xbot")
                              ? j.at("control_parameters").at("xbot")
                              : json::object();
        jd.control.mode = control_mode_from_xbot(str(xbot, "control_mode"));
        if (xbot.contains("pid") && xbot.at("pid").is_object()) {
          const json& pid = xbot.at("pid");
          if (pid.contains("impedance") && pid.at("impedance").is_array() && pid.at("impedance").size() >= 2) {
            jd.control.stiffness = num(pid.at("impedance")[0], file, p + "control_parameters.xbot.pid.impedance[0]");
            jd.control.damping = num(pid.at("impedance")[1], file, p + "control_parameters.xbot.pid.impedance[1]");
          }
          for (const char* key : {"position", "velocity"}) {
            if (pid.contains(key) && pid.at(key).is_array() && pid.at(key).size() == 3) {
              const Eigen::Vector3d g = vec3(pid.at(key), file, p + "control_parameters.xbot.pid." + key);
              jd.control.kp = g[0];
              jd.control.ki = g[1];
              jd.control.kd = g[2];
              break;
            }
          }
        }
      } else {
        fail(file, p + "type", "unknown joint type '" + type + "'");
      }
      m.joints.push_back(std::move(jd));
    });
  }
  // Semantic tags from the type.
  if (m.type == ModuleType::kWheel) m.tags.push_back("leg");
  if (m.type == ModuleType::kEndEffector) m.tags.push_back("arm");
  detail::validate_and_normalise(m, file);
  return m;
}

AddonDescription load_json_addon(const fs::path& file) {
  const json doc = read_json(file);
  AddonDescription a;
  const json& header = read_header(doc, file, a);
  a.type = str(header, "type");
  if (a.type.empty()) fail(file, "header.type", "missing");
  const json& params = req(doc, "parameters", file, "");
  if (!params.is_object()) fail(file, "parameters", "expected an object");
  for (auto it = params.begin(); it != params.end(); ++it) {
    a.parameters[it.key()] = num(it.value(), file, "parameters." + it.key());
  }
  a.mass = req_num(params, "mass", file, "parameters.");
  if (a.mass < 0.0) fail(file, "parameters.mass", "must be >= 0");
  if (a.type == "drillbit") {
    // The bit extends the tool along the TCP z axis by its length; its CoM sits half-way.
    a.tcp_offset = req_num(params, "length", file, "parameters.");
    a.com = Eigen::Vector3d(0.0, 0.0, a.tcp_offset / 2.0);
  } else if (a.type == "handle") {
    a.com = Eigen::Vector3d(req_num(params, "x_offset", file, "parameters."), req_num(params, "y_offset", file, "parameters."),
                            req_num(params, "z_offset", file, "parameters."));
  }
  return a;
}

}  // namespace concert::module_db
