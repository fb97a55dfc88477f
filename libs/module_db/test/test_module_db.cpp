#include <fstream>
#include <random>

#include <gtest/gtest.h>
#include <nlohmann/json.hpp>

#include "concert/common/error_text.hpp"
#include "concert/module_db/module_db.hpp"
#include "concert/topology/esc_catalog.hpp"

namespace fs = std::filesystem;
using namespace concert::module_db;

namespace {

const fs::path kPublic = fs::path(CONCERT_SHARED_DATA) / "concert_resources";
const fs::path kOwn = fs::path(CONCERT_SOURCE_DIR) / "data" / "module_db";

/// A fresh scratch folder per test.
fs::path scratch(const std::string& name) {
  fs::path dir = fs::temp_directory_path() / ("concert_module_db_test_" + name + "_" + std::to_string(::getpid()));
  fs::remove_all(dir);
  fs::create_directories(dir);
  return dir;
}

std::string error_of(const std::function<void()>& f) { return concert::error_text<ModuleDbError>(f); }

}  // namespace

TEST(PublicDatabase, LoadsEveryModuleAndAddon) {
  const ModuleDatabase db = load_module_database(kPublic);
  EXPECT_EQ(db.size(), 28u);
  EXPECT_EQ(db.addon_keys().size(), 8u);
  const ModuleDescription& elbow = db.at("module_joint_elbow_A_concert");
  EXPECT_EQ(elbow.type, ModuleType::kJoint);
  ASSERT_EQ(elbow.bodies.size(), 2u);
  ASSERT_EQ(elbow.joints.size(), 1u);
  EXPECT_DOUBLE_EQ(elbow.joints[0].limits.velocity, 2.14);
  EXPECT_DOUBLE_EQ(elbow.joints[0].limits.peak_torque, 460.0);
  EXPECT_DOUBLE_EQ(elbow.joints[0].gear_ratio, 160.0);
  EXPECT_EQ(elbow.joints[0].control.mode, "impedance");
  ASSERT_TRUE(elbow.esc.has_value());
  EXPECT_EQ(*elbow.esc, (concert::topology::EscIdentity{1, 6, 4, 0}));
  EXPECT_EQ(db.find_by_identity({1, 6, 4, 0}), &elbow);
  EXPECT_NEAR(elbow.mass(), 3.6144181 + 1.1481338, 1e-12);
  EXPECT_EQ(elbow.output_connectors().size(), 1u);
  EXPECT_EQ(elbow.root_body(), 0);
}

TEST(PublicDatabase, MobileBaseConnectorsFollowTheNumberingContract) {
  const ModuleDatabase db = load_module_database(kPublic);
  const ModuleDescription& base = db.at("mobile_platform_concert");
  EXPECT_EQ(base.type, ModuleType::kMobileBase);
  const std::vector<int> outs = base.output_connectors();
  ASSERT_EQ(outs.size(), 5u);
  for (size_t n = 0; n < outs.size(); ++n) {
    EXPECT_EQ(base.connectors[static_cast<size_t>(outs[n])].name, "2300_connector_" + std::to_string(n + 1));
  }
  // Leg 1 is front-left (+x, +y), leg 4 rear-right.
  EXPECT_GT(base.connectors[static_cast<size_t>(outs[0])].pose.translation().x(), 0.0);
  EXPECT_GT(base.connectors[static_cast<size_t>(outs[0])].pose.translation().y(), 0.0);
  EXPECT_LT(base.connectors[static_cast<size_t>(outs[3])].pose.translation().x(), 0.0);
  EXPECT_LT(base.connectors[static_cast<size_t>(outs[3])].pose.translation().y(), 0.0);
  EXPECT_EQ(base.input_connector(), -1);
  EXPECT_FALSE(db.port_routes().empty());
}

TEST(PublicDatabase, TypesFromHeaderAndIndex) {
  const ModuleDatabase db = load_module_database(kPublic);
  EXPECT_EQ(db.at("module_base_link_600_concert").type, ModuleType::kBaseLink);
  EXPECT_EQ(db.at("module_link_straight_400_concert").type, ModuleType::kLink);
  EXPECT_EQ(db.at("module_Y_torso_concert").type, ModuleType::kHub);
  EXPECT_EQ(db.at("module_Y_torso_concert").output_connectors().size(), 2u);
  const ModuleDescription& wheel = db.at("module_wheel_concert");
  EXPECT_EQ(wheel.type, ModuleType::kWheel);
  EXPECT_EQ(wheel.joints[0].type, JointType::kContinuous);
  EXPECT_EQ(wheel.joints[0].control.mode, "velocity");
  EXPECT_TRUE(wheel.output_connectors().empty());
  EXPECT_EQ(wheel.tcp_connectors().size(), 1u);
  const ModuleDescription& drill = db.at("module_drill_concert");
  EXPECT_EQ(drill.type, ModuleType::kEndEffector);
  EXPECT_EQ(drill.tcp_connectors().size(), 1u);
  EXPECT_EQ(drill.addon_types, (std::vector<std::string>{"drillbit", "handle"}));
  // The Timor planar base uses Python's Infinity: loaded as unbounded.
  const ModuleDescription& planar = db.at("mobile_platform_concert_timor_planar");
  EXPECT_EQ(planar.joints.size(), 3u);
  EXPECT_EQ(planar.joints[2].type, JointType::kContinuous);
}

TEST(PublicDatabase, AddonsCarryMassAndTcpOffset) {
  const ModuleDatabase db = load_module_database(kPublic);
  const AddonDescription* bit = db.find_addon("drillbit_16_SDSplus");
  ASSERT_NE(bit, nullptr);
  EXPECT_EQ(bit->type, "drillbit");
  EXPECT_DOUBLE_EQ(bit->mass, 0.8);
  EXPECT_DOUBLE_EQ(bit->tcp_offset, 0.336);
  const AddonDescription* handle = db.find_addon("drill_handle");
  ASSERT_NE(handle, nullptr);
  EXPECT_DOUBLE_EQ(handle->com.y(), 0.25);
}

TEST(JsonErrors, NameFileAndField) {
  const fs::path dir = scratch("json");
  nlohmann::json doc;
  {
    std::ifstream in(kPublic / "json/concert/module_joint_elbow_A_concert.json");
    in >> doc;
  }
  auto write = [&](const nlohmann::json& d) {
    std::ofstream(dir / "module_joint_elbow_A_concert.json") << d.dump(2);
    return dir / "module_joint_elbow_A_concert.json";
  };
  nlohmann::json no_velocity = doc;
  no_velocity["joints"][0]["limits"].erase("velocity");
  EXPECT_EQ(error_of([&] { load_json_module(write(no_velocity)); }),
            "module_joint_elbow_A_concert.json: joints[0].limits.velocity: missing");
  nlohmann::json bad_mass = doc;
  bad_mass["bodies"][1]["mass"] = "heavy";
  EXPECT_EQ(error_of([&] { load_json_module(write(bad_mass)); }),
            "module_joint_elbow_A_concert.json: bodies[1].mass: not a number");
  nlohmann::json bad_child = doc;
  bad_child["joints"][0]["child"] = "nowhere";
  EXPECT_EQ(error_of([&] { load_json_module(write(bad_child)); }),
            "module_joint_elbow_A_concert.json: joints[0].child: no body 'nowhere'");
  nlohmann::json bad_pose = doc;
  bad_pose["joints"][0]["pose_parent"][0][0] = 2.0;
  EXPECT_EQ(error_of([&] { load_json_module(write(bad_pose)); }),
            "module_joint_elbow_A_concert.json: joints[0].pose_parent: rotation part is not a rotation matrix");
  nlohmann::json bad_type = doc;
  bad_type["header"]["type"] = "teleporter";
  EXPECT_EQ(error_of([&] { load_json_module(write(bad_type)); }),
            "module_joint_elbow_A_concert.json: header.type: unknown module type 'teleporter'");
  std::ofstream(dir / "broken.json") << "{ \"header\": ";
  EXPECT_NE(error_of([&] { load_json_module(dir / "broken.json"); }).find("broken.json: (document): invalid JSON"),
            std::string::npos);
  // Found by tests/fuzz: the JSON library's out_of_range (a number beyond double) escaped.
  std::ofstream(dir / "huge.json") << "{ \"header\": {\"type\": \"link\"}, \"mass\": 1e400 }";
  EXPECT_NE(error_of([&] {
              load_json_module(dir / "huge.json");
            }).find("huge.json: (document): invalid JSON"),
            std::string::npos);
  // Found by tests/fuzz: modelgen wrote these into URDF that urdfdom refuses (lower="-inf",
  // a colour component beyond float).
  nlohmann::json one_limit = doc;
  one_limit["joints"][0]["limits"].erase("positionLower");
  EXPECT_EQ(error_of([&] { load_json_module(write(one_limit)); }),
            "module_joint_elbow_A_concert.json: joints[0].limits: lower and upper position limits "
            "required (a revolute joint without both is continuous)");
  nlohmann::json bad_colour = doc;
  bad_colour["bodies"][1]["visual"][0]["parameters"]["color"]["rgba"][2] = 1e39;
  EXPECT_EQ(error_of([&] { load_json_module(write(bad_colour)); }),
            "module_joint_elbow_A_concert.json: bodies[1].visual[0].rgba: components must be "
            "within 0..1");
  fs::remove_all(dir);
}

TEST(YamlErrors, NameFileAndField) {
  const fs::path dir = scratch("yaml");
  const std::string good = R"(type: link
bodies:
  - {name: link, mass: 1.0, com: [0, 0, 0.1], inertia: [0.01, 0.01, 0.01, 0, 0, 0]}
connectors:
  - {name: input, role: input, body: link, size: large}
  - {name: output, role: output, body: link, size: large, pose: {xyz: [0, 0, 0.2]}}
)";
  std::ofstream(dir / "good_link.yaml") << good;
  const ModuleDescription m = load_yaml_module(dir / "good_link.yaml");
  EXPECT_EQ(m.key, "good_link");
  EXPECT_DOUBLE_EQ(m.connectors[1].pose.translation().z(), 0.2);

  // `good` with `what` replaced by `with`, written as `name` in the scratch folder.
  auto edited = [&](const std::string& name, const std::string& what, const std::string& with) {
    std::string text = good;
    text.replace(text.find(what), what.size(), with);
    std::ofstream(dir / name) << text;
    return dir / name;
  };
  EXPECT_EQ(error_of([&] {
              load_yaml_module(edited("no_mass.yaml", "mass: 1.0, ", ""));
            }).rfind("no_mass.yaml: bodies[0].mass: missing", 0),
            0u);
  EXPECT_EQ(error_of([&] {
              load_yaml_module(edited("bad_role.yaml", "role: output", "role: sideways"));
            }),
            "bad_role.yaml: connectors[1].role: unknown role 'sideways' (expected input, output, "
            "tcp, base)");
  EXPECT_EQ(error_of([&] {
              load_yaml_module(edited("bad_body.yaml", "body: link, size: large, pose",
                                      "body: lnk, size: large, pose"));
            }),
            "bad_body.yaml: connectors[1].body: no body 'lnk'");
  // Found by tests/fuzz: yaml-cpp's BadSubscript escaped for a shape that is not a mapping.
  EXPECT_EQ(error_of([&] {
              load_yaml_module(edited("scalar_shape.yaml", "inertia: [0.01, 0.01, 0.01, 0, 0, 0]}",
                                      "inertia: [0.01, 0.01, 0.01, 0, 0, 0], collision: [oops]}"));
            }),
            "scalar_shape.yaml: bodies[0].collision[0]: expected a mapping (line 3)");
  // Found by tests/fuzz: yaml-cpp reads bytes that are not UTF-8 as they come, and they reached
  // the generated URDF, which the services refuse.
  EXPECT_EQ(error_of([&] {
              load_yaml_module(edited("not_utf8.yaml", "name: input", "name: in\xfc\xfc"));
            }),
            "not_utf8.yaml: (document): not valid UTF-8 (byte " +
                std::to_string(good.find("name: input") + 8) + ")");
  fs::remove_all(dir);
}

TEST(Database, DuplicateKeysAndUnknownKeysAreErrors) {
  ModuleDatabase a = load_module_database(kPublic);
  EXPECT_NE(error_of([&] { a.merge(load_module_database(kPublic)); }).find("already defined by"), std::string::npos);
  EXPECT_EQ(error_of([&] { (void)a.at("no_such_module"); }), "unknown module key 'no_such_module'");
  EXPECT_EQ(error_of([&] { load_module_database(kPublic / "models"); }).find("not a module database"),
            (kPublic / "models").string().size() + 2);
}

TEST(OwnDatabase, DescribesEveryModuleOfThePaper) {
  const ModuleDatabase db = load_module_database(kOwn);
  const std::vector<std::string> keys{"concert_mobile_base_hub", "concert_steering_fl_rr", "concert_steering_fr_rl", "concert_wheel",
                                      "concert_elbow_a", "concert_elbow_b", "concert_straight_a", "concert_straight_b",
                                      "concert_link_300", "concert_link_400", "concert_link_elbow_45", "concert_link_elbow_90",
                                      "concert_base_link_600", "concert_torso_hub", "concert_drill", "concert_spraying_tool",
                                      "concert_sanding_tool", "concert_active_gripper_panel", "concert_active_gripper_tube",
                                      "concert_passive_gripper_panel", "concert_passive_gripper_tube"};
  EXPECT_EQ(db.module_keys().size(), keys.size());
  for (const std::string& k : keys) EXPECT_NE(db.find(k), nullptr) << k;
  const ModuleDescription& base = db.at("concert_mobile_base_hub");
  EXPECT_EQ(base.type, ModuleType::kMobileBase);
  EXPECT_EQ(base.output_connectors().size(), 5u);
  EXPECT_EQ(base.connectors[static_cast<size_t>(base.output_connectors()[4])].name, "arm");
  EXPECT_EQ(db.at("concert_torso_hub").output_connectors().size(), 2u);
  EXPECT_EQ(db.at("concert_base_link_600").type, ModuleType::kBaseLink);
  EXPECT_NEAR(db.at("concert_base_link_600").connectors[1].pose.translation().z(), 0.6, 1e-12);
  const ModuleDescription& drill = db.at("concert_drill");
  ASSERT_EQ(drill.frames.size(), 1u);
  EXPECT_EQ(drill.frames[0].kind, FrameKind::kCamera);
  std::vector<FrameKind> kinds;
  for (const Frame& f : drill.named_frames()) kinds.push_back(f.kind);
  EXPECT_EQ(kinds, (std::vector<FrameKind>{FrameKind::kInput, FrameKind::kTcp, FrameKind::kCamera}));
  kinds.clear();
  for (const Frame& f : db.at("concert_wheel").named_frames()) kinds.push_back(f.kind);
  EXPECT_EQ(kinds, (std::vector<FrameKind>{FrameKind::kInput, FrameKind::kJoint, FrameKind::kWheel}));
  kinds.clear();
  for (const Frame& f : db.at("concert_elbow_a").named_frames()) kinds.push_back(f.kind);
  EXPECT_EQ(kinds, (std::vector<FrameKind>{FrameKind::kInput, FrameKind::kJoint, FrameKind::kOutput}));
  EXPECT_FALSE(db.at("concert_passive_gripper_panel").esc.has_value());
  EXPECT_FALSE(db.at("concert_passive_gripper_panel").actuated());
  EXPECT_TRUE(db.at("concert_active_gripper_panel").actuated());
  EXPECT_EQ(db.addon_keys().size(), 4u);
  ASSERT_NE(db.find_addon("concert_sanding_force_sensor"), nullptr);
  EXPECT_TRUE(db.find_addon("concert_sanding_force_sensor")->frame.has_value());
}

TEST(OwnDatabase, ActuatorLimitsAreTable1) {
  const ModuleDatabase db = load_module_database(kOwn);
  struct Row {
    const char* key;
    const char* actuator;
    double gear, velocity, peak, continuous, mass;
  };
  const Row rows[] = {{"concert_elbow_a", "Large A", 160, 2.14, 460, 160, 2.5},       {"concert_straight_a", "Large A", 160, 2.14, 460, 160, 2.5},
                      {"concert_elbow_b", "Large B", 120, 2.85, 314, 120, 2.0},       {"concert_straight_b", "Large B", 120, 2.85, 314, 120, 2.0},
                      {"concert_steering_fl_rr", "Medium", 120, 8.1, 127, 34, 1.3},   {"concert_active_gripper_tube", "Small A", 100, 11.7, 55, 17, 1.0},
                      {"concert_wheel", "Small B", 29, 13.7, 24, 17.5, 2.7}};
  for (const Row& r : rows) {
    const ModuleDescription& m = db.at(r.key);
    ASSERT_EQ(m.joints.size(), 1u) << r.key;
    const JointDescription& j = m.joints[0];
    EXPECT_DOUBLE_EQ(j.gear_ratio, r.gear) << r.key;
    EXPECT_DOUBLE_EQ(j.limits.velocity, r.velocity) << r.key;
    EXPECT_DOUBLE_EQ(j.limits.peak_torque, r.peak) << r.key;
    ASSERT_TRUE(j.limits.continuous_torque.has_value()) << r.key;
    EXPECT_DOUBLE_EQ(*j.limits.continuous_torque, r.continuous) << r.key;
    ASSERT_TRUE(m.actuator.has_value()) << r.key;
    EXPECT_EQ(m.actuator->name, r.actuator);
    EXPECT_DOUBLE_EQ(m.actuator->mass, r.mass) << r.key;
  }
  EXPECT_EQ(db.at("concert_wheel").joints[0].type, JointType::kContinuous);
}

TEST(OwnDatabase, EscIndexReusesPublicIdentities) {
  const ModuleDatabase own = load_module_database(kOwn);
  const ModuleDatabase pub = load_module_database(kPublic);
  const std::pair<const char*, const char*> same[] = {
      {"concert_elbow_a", "module_joint_elbow_A_concert"},   {"concert_elbow_b", "module_joint_elbow_B_concert"},
      {"concert_straight_a", "module_joint_yaw_A_concert"},  {"concert_straight_b", "module_joint_yaw_B_concert"},
      {"concert_steering_fl_rr", "module_steering_concert_fl_rr"}, {"concert_wheel", "module_wheel_concert"},
      {"concert_mobile_base_hub", "mobile_platform_concert"}, {"concert_torso_hub", "module_Y_torso_concert"},
      {"concert_drill", "module_drill_concert"},             {"concert_base_link_600", "module_base_link_600_concert"},
      {"concert_link_400", "module_link_straight_400_concert"}};
  for (const auto& [mine, theirs] : same) {
    ASSERT_TRUE(own.at(mine).esc.has_value()) << mine;
    EXPECT_EQ(*own.at(mine).esc, *pub.at(theirs).esc) << mine;
  }
  EXPECT_EQ(own.find_by_identity({2, 4, 0, 0}), &own.at("concert_mobile_base_hub"));
  const EscIndex index = load_esc_index(kOwn / "esc_index.yaml");
  int project_assigned = 0;
  for (const EscIndexEntry& e : index.modules) project_assigned += e.project_assigned ? 1 : 0;
  EXPECT_EQ(project_assigned, 4);
  EXPECT_EQ(index.ports.size(), 6u);
}

TEST(OwnDatabase, DiscoveryCatalogueReadsOurEscIndex) {
  // The discovery engineer's loader reads the same file: its connector layout must agree with
  // our connector numbering contract.
  const auto catalog = concert::topology::EscCatalog::load(kOwn);
  const ModuleDatabase db = load_module_database(kOwn);
  for (const auto& entry : catalog.entries()) {
    const ModuleDescription* m = db.find(entry.key);
    ASSERT_NE(m, nullptr) << entry.key;
    if (entry.identity == concert::topology::EscIdentity{2, 4, 0, 0}) continue;  // hub board: secondary ESC
    const auto layout = catalog.layout(entry.identity);
    EXPECT_EQ(static_cast<size_t>(layout.outputs()), m->output_connectors().size()) << entry.key;
  }
}

TEST(EscIndexFile, ProjectExtensionsAndErrors) {
  const fs::path dir = scratch("esc_index");
  std::ofstream(dir / "esc_index.yaml") << R"(modules:
  - {mod_type: 2, mod_id: 9, mod_size: 4, mod_rev: 1, file: modules/hub3.yaml, key: my_hub, outputs: 3, project_assigned: true,
     ports: [{port: 3, leads_to: 1}, {port: 1, leads_to: 2}, {port: 2, leads_to: 3}]}
  - {mod_type: 1, mod_id: 6, mod_size: 4, mod_rev: 0, file: modules/elbow.yaml}
module_ports:
  - {mod_type: 2, mod_id: 9, port: 2, leads_to: hub_board}
)";
  const EscIndex index = load_esc_index(dir / "esc_index.yaml");
  ASSERT_EQ(index.modules.size(), 2u);
  EXPECT_EQ(index.modules[0].key, "my_hub");
  EXPECT_EQ(index.modules[0].outputs, 3);
  EXPECT_TRUE(index.modules[0].project_assigned);
  EXPECT_EQ(index.modules[1].key, "elbow");
  EXPECT_FALSE(index.modules[1].project_assigned);
  ASSERT_EQ(index.ports.size(), 4u);
  EXPECT_EQ(index.ports[0].port, 3);
  EXPECT_EQ(index.ports[0].leads_to, "1");
  EXPECT_EQ(index.ports[3].leads_to, "hub_board");
  std::ofstream(dir / "bad_index.yaml") << "modules:\n  - {mod_type: 1, mod_size: 4, mod_rev: 0, file: x.yaml}\n";
  EXPECT_EQ(error_of([&] { load_esc_index(dir / "bad_index.yaml"); }), "bad_index.yaml: modules[0].mod_id: missing");
  std::ofstream(dir / "bad_port.yaml") << "modules: []\nmobile_base_ports:\n  - {mod_type: 2, mod_id: 3, port: 7, leads_to: 1}\n";
  EXPECT_EQ(error_of([&] { load_esc_index(dir / "bad_port.yaml"); }), "bad_port.yaml: mobile_base_ports[0].port: must be 0..3");
  // Found by tests/fuzz: yaml-cpp's BadSubscript escaped for a document or row of another kind.
  std::ofstream(dir / "not_a_map.yaml") << "just text\n";
  EXPECT_EQ(error_of([&] { load_esc_index(dir / "not_a_map.yaml"); }),
            "not_a_map.yaml: (document): expected a mapping with a 'modules:' list");
  std::ofstream(dir / "scalar_row.yaml") << "modules: [5]\n";
  EXPECT_EQ(error_of([&] { load_esc_index(dir / "scalar_row.yaml"); }),
            "scalar_row.yaml: modules[0]: expected a mapping");
  fs::remove_all(dir);
}
