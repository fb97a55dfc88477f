#pragma once
// Shared helpers of the modelgen tests: the two module databases, tree construction, the robots
// the tests build (the public 18-module robot, the paper's morphologies from the project
// database), the same robots as assembly files, and two independent forward-kinematics
// evaluations (URDF tree walk and eq. 1-2 over module descriptions).

#include <functional>
#include <map>
#include <string>
#include <tuple>
#include <vector>

#include <urdf_model/model.h>

#include "concert/module_db/module_db.hpp"
#include "concert/simbus/assembly.hpp"
#include "concert/topology/types.hpp"
#include "modelgen/model_generator.hpp"

namespace concert::modelgen::test {

/// The public CONCERT database (../shared/data/concert_resources), loaded once per test binary.
const module_db::ModuleDatabase& public_db();
/// The project's database (data/module_db), loaded once per test binary.
const module_db::ModuleDatabase& own_db();

/// Message of the ModelError `f` throws, or "(no error)".
std::string error_of(const std::function<void()>& f);

/// One module row: key, parent module index (-1 root), parent output connector (1-based).
using Row = std::tuple<std::string, int, int>;

/// A module tree from rows (ESC identities looked up in `db` when known).
topology::ModuleTree make_tree(const std::vector<Row>& rows, const module_db::ModuleDatabase* db = nullptr);

/// The public database's 18-module robot: mobile base, four steering+wheel legs, arm of yaw A,
/// elbow A, link 0.4, elbow A, yaw B, link 0.4, elbow B, yaw B, panel gripper (connector 5).
std::vector<Row> public_eighteen_module_robot();

/// Project database: the mobile base with its four legs, then `arm` in a chain on connector 5.
std::vector<Row> mobile_robot(const std::vector<std::string>& arm);
/// Paper section 6.1: morphology A = Straight A, Elbow A, Straight A, Elbow A, Straight B, link
/// 0.4, Elbow B, Drill; B adds a 0.4 m link after the third joint (C: A behind a base link).
extern const std::vector<std::string> kMorphologyA;
extern const std::vector<std::string> kMorphologyB;
/// Project database: the mobile base, a 0.6 m base link and the torso hub with two arms (a
/// gripper arm on connector 1, a sanding arm on connector 2).
std::vector<Row> two_arm_torso();

/// The rows as an assembly file mounts them (module i is named "m<i>"), for the simulated bus.
simbus::Assembly to_assembly(const std::vector<Row>& rows);

/// Link pose in the root link frame by walking the urdfdom tree; q by joint name (default 0).
Eigen::Isometry3d urdf_fk(const urdf::ModelInterface& model, const std::string& link, const std::map<std::string, double>& q);

/// Pose of TCP connector `tcp_index` of module `module` in the root body frame, composed with eq.
/// (1)-(2) directly from the module descriptions; q[module][joint index in the description].
Eigen::Isometry3d description_fk(const module_db::ModuleDatabase& db, const topology::ModuleTree& tree, int module, int tcp_index,
                                 const std::map<int, std::map<int, double>>& q);

}  // namespace concert::modelgen::test
