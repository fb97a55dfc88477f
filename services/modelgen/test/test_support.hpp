#pragma once
// Shared helpers of the modelgen tests: tree construction, the public 18-module robot, and two
// independent forward-kinematics evaluations (URDF tree walk and eq. 1-2 over module descriptions).

#include <map>
#include <string>
#include <tuple>
#include <vector>

#include <urdf_model/model.h>

#include "concert/module_db/module_db.hpp"
#include "concert/topology/types.hpp"
#include "modelgen/model_generator.hpp"

namespace concert::modelgen::test {

/// One module row: key, parent module index (-1 root), parent output connector (1-based).
using Row = std::tuple<std::string, int, int>;

/// A module tree from rows (ESC identities looked up in `db` when known).
topology::ModuleTree make_tree(const std::vector<Row>& rows, const module_db::ModuleDatabase* db = nullptr);

/// The public database's 18-module robot: mobile base, four steering+wheel legs, arm of yaw A,
/// elbow A, link 0.4, elbow A, yaw B, link 0.4, elbow B, yaw B, panel gripper (connector 5).
std::vector<Row> public_eighteen_module_robot();

/// Link pose in the root link frame by walking the urdfdom tree; q by joint name (default 0).
Eigen::Isometry3d urdf_fk(const urdf::ModelInterface& model, const std::string& link, const std::map<std::string, double>& q);

/// Pose of TCP connector `tcp_index` of module `module` in the root body frame, composed with eq.
/// (1)-(2) directly from the module descriptions; q[module][joint index in the description].
Eigen::Isometry3d description_fk(const module_db::ModuleDatabase& db, const topology::ModuleTree& tree, int module, int tcp_index,
                                 const std::map<int, std::map<int, double>>& q);

}  // namespace concert::modelgen::test
