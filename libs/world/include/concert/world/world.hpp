#pragma once

#include <Eigen/Core>

#include <stdexcept>
#include <string>
#include <vector>

namespace concert::world {

/// Bad world file (names the file and the field).
class WorldError : public std::runtime_error {
 public:
  using std::runtime_error::runtime_error;
};

/// A box or a vertical cylinder standing in the world.
struct WorldShape {
  enum class Type { kBox, kCylinder };
  std::string name;
  Type type{Type::kBox};
  Eigen::Vector3d size{1.0, 1.0, 1.0};   ///< box: full extents x y z [m]; cylinder: radius, -, height [m]
  Eigen::Vector3d position{0, 0, 0};     ///< centre in the world frame [m]
  double yaw{0.0};                       ///< rotation about world z [rad]
  double friction{1.0};                  ///< sliding friction coefficient [-]
};

/// The simulated world: a floor, walls and obstacles (see README "World file").
struct World {
  bool floor{true};
  double floor_height{0.0};    ///< [m]
  double floor_friction{1.0};  ///< [-]
  std::vector<WorldShape> walls;
  std::vector<WorldShape> obstacles;
};

/// Parses world YAML text; `source` names the file in error messages.
World parse_world_yaml(const std::string& text, const std::string& source = "<string>");
/// Reads a world YAML file.
World load_world_file(const std::string& path);

}  // namespace concert::world
