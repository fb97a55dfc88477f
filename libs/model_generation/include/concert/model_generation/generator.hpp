#pragma once
// Module tree (chi) + module database -> physical tree (phi) -> URDF, SRDF, controller config.
//
// Naming contract (paper section 4.3.3; downstream configs depend on it):
//  * chain tags A, B, C, ... (then AA, AB, ...) are handed out depth-first, children in order of
//    the parent's output connector number; a new chain starts only at a hub output (the root
//    module starts chain A unless it is a hub);
//  * the joint index j starts at 0 per chain and increments after each moving joint; the link
//    index l counts passive bodies (links, hubs, passive end-effectors) since the last moving
//    joint and resets to 0 at each moving joint;
//  * root body: `base_link`; passive link: `L_<j>_link_<l>_<T>`; hub: `L_<j>_hub_<l>_<T>`;
//    proximal body of a joint module: `L_<j>_proximal_<T>`; moving joint: `J<j>_<T>` (j after the
//    increment); body after it: `L_<j>_<T>`; passive end-effector body: `L_<j>_ee_<T>`;
//    TCP / wheel centre: `tcp_<T>` / `wheel_<T>` (a second one: `tcp2_<T>`); other frames:
//    `<frame>_<T>`; static joints: `fixed_<child link>`. Without a tag the suffix is dropped.
//  * end-effector names: `<first semantic tag>_<T>`, e.g. `drill_E`, `wheel_A`.

#include <vector>

#include "concert/module_db/module_db.hpp"
#include "concert/topology/types.hpp"
#include "concert/model_generation/model.hpp"

namespace concert::model_generation {

/// Immutable generator over one database. generate() is const and thread-compatible.
class ModelGenerator {
 public:
  /// The database must outlive the generator and every model it produces (phi points into it).
  ModelGenerator(const module_db::ModuleDatabase& db, Params params = {});

  /// Builds the physical tree only. Throws ModelError.
  PhysicalTree build_tree(const topology::ModuleTree& tree, const Customisation& custom = {}) const;

  /// Builds the whole model (texts, lists, hash); version stays 0. Throws ModelError; the
  /// caller's current model is not touched. A tree with errors (check_modelable) or unknown
  /// modules is refused, naming each unknown module's slave position and identity. An add-on choice
  /// whose `addon` is the key of a module without ESC (a passive gripper, which the network cannot
  /// see) mounts that module on the first free output connector of the module owning body
  /// `module_name`, or of the last module of chain `module_name` (e.g. "E").
  GeneratedModel generate(const topology::ModuleTree& tree, const Customisation& custom = {},
                      uint64_t tree_version = 0) const;

  /// The description used for module node `node` (by key, else by ESC identity). Throws
  /// ModelError naming the module.
  const module_db::ModuleDescription& describe(const topology::ModuleNode& node) const;

  const Params& params() const { return params_; }

  /// `tree` with the passive modules named in `custom.addons` mounted (see generate()).
  topology::ModuleTree mount_passive_modules(const topology::ModuleTree& tree, const Customisation& custom) const;

 private:
  const module_db::ModuleDatabase& db_;
  Params params_;
};

/// Throws ModelError if a model cannot be built from `tree` whatever the database: the tree has
/// errors (it is undefined there), or unknown modules (each named by slave position and identity).
void check_modelable(const topology::ModuleTree& tree);

/// URDF text of a physical tree (fixed joints kept).
std::string write_urdf(const PhysicalTree& tree, const std::string& robot_name);
/// SRDF text: a group per chain, arms/legs/wheels groups, `chains` group, end-effectors, `home`
/// group state, disabled collisions between adjacent bodies.
std::string write_srdf(const GeneratedModel& model, const std::string& robot_name);
/// Controller configuration YAML (joints with limits, gains, control modes, home; chains;
/// end-effectors); the robot service reads it.
std::string write_config_yaml(const GeneratedModel& model, const std::string& robot_name);
/// "sha256:<64 hex digits>" of `text`.
std::string sha256_hex(const std::string& text);

}  // namespace concert::model_generation
