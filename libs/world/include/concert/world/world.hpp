#pragma once

#include <Eigen/Core>
#include <optional>
#include <stdexcept>
#include <string>
#include <vector>

namespace concert::world {

/// Bad world file (names the file and the field).
class WorldError : public std::runtime_error {
 public:
  using std::runtime_error::runtime_error;
};

/// How a moving obstacle runs through its waypoints.
struct ObstaclePath {
  enum class Mode {
    kLoop,      ///< start -> waypoints -> back to the start, again and again
    kPingPong,  ///< start -> waypoints, then back the same way, again and again
    kOnce,      ///< start -> waypoints, then stays at the last waypoint
  };
  std::vector<Eigen::Vector2d> waypoints;  ///< x y in the world frame [m]; at least one
  double speed{0.5};                       ///< constant speed along the path [m/s], > 0
  Mode mode{Mode::kLoop};
};

/// A box or a vertical cylinder standing in the world.
struct WorldShape {
  enum class Type { kBox, kCylinder };
  std::string name;
  Type type{Type::kBox};
  Eigen::Vector3d size{1.0, 1.0,
                       1.0};  ///< box: full extents x y z [m]; cylinder: radius, -, height [m]
  Eigen::Vector3d position{0, 0,
                           0};  ///< centre in the world frame [m] (a moving obstacle: at t = 0)
  double yaw{0.0};              ///< rotation about world z [rad]
  double friction{1.0};         ///< sliding friction coefficient [-]
  /// Obstacles only: moves piecewise linearly from `position` through the waypoints (z and yaw
  /// fixed); see obstacle_position() in geometry.hpp.
  std::optional<ObstaclePath> path;
};

/// A vertical face of a wall box, named by the box's local axis before its yaw.
///
/// Face conventions (README "World file", geometry.hpp face_frame()):
/// * outward normal n = R(yaw) * axis (+x, -x, +y or -y of the box);
/// * in-face horizontal axis u = z^ x n: it points to the viewer's right when looking at the
///   face from outside (towards -n), so (u, z^, n) is a right-handed frame;
/// * a point on the face is given as `at: [u, z]`: the offset along u from the face centre [m]
///   and the height z in the world frame [m].
enum class Face { kPlusX, kMinusX, kPlusY, kMinusY };

/// A visual mark on a wall face: a blue disc (blob) or an ArUco marker. Marks are thin visual
/// geoms (no collision) whose front surface is 1 mm in front of the face (kMarkStandoff).
struct Mark {
  enum class Type { kBlob, kAruco };
  std::string name;  ///< unique in the world
  Type type{Type::kBlob};
  std::string wall;  ///< name of the wall it is on
  Face face{Face::kPlusX};
  Eigen::Vector2d at{0, 0};  ///< centre: [u offset from the face centre, world height z] [m]
  // Blob.
  double diameter{0.1};                       ///< [m]
  Eigen::Vector4d rgba{0.05, 0.1, 0.9, 1.0};  ///< colour [0..1]
  // ArUco.
  double size{0.1};  ///< full outer side, black border included (OpenCV markerLength) [m]
  std::string dictionary{"DICT_4X4_50"};  ///< OpenCV predefined dictionary name (aruco.hpp)
  int id{0};                              ///< marker id in the dictionary
  double angle{0.0};  ///< rotation about n, counter-clockwise as seen from the front [rad]
};

/// Distance of a mark's front surface in front of its wall face [m].
inline constexpr double kMarkStandoff = 0.001;

/// A smooth bump (height > 0) or a hole (height = its depth) of a sanding surface, with the
/// cosine profile h(r) = height * (1 + cos(pi r / radius)) / 2 for r < radius, 0 beyond.
struct SurfaceFeature {
  Eigen::Vector2d at{0, 0};  ///< centre [u, z] in the face's coordinates (as Mark::at) [m]
  double radius{0.05};       ///< [m]
  double height{0.002};      ///< bump height or hole depth [m], > 0
};

/// A plaster layer on a wall face, to be sanded: its nominal surface is `thickness` in front of
/// the face, bumps stand out of it and holes go into it (surface_height() in geometry.hpp).
struct Surface {
  std::string name;  ///< unique in the world
  std::string wall;
  Face face{Face::kPlusX};
  Eigen::Vector2d at{0, 0};        ///< centre [u, z] (as Mark::at) [m]
  Eigen::Vector2d size{1.0, 1.0};  ///< width along u, height along z [m]
  double thickness{0.01};          ///< nominal layer thickness [m]
  double resolution{0.005};        ///< height-field grid spacing in the simulator [m]
  std::vector<SurfaceFeature> bumps;
  std::vector<SurfaceFeature> holes;  ///< depth < thickness
};

/// The simulated world: a floor, walls, obstacles, marks and sanding surfaces on the walls
/// (see README "World file").
struct World {
  bool floor{true};
  double floor_height{0.0};    ///< [m]
  double floor_friction{1.0};  ///< [-]
  std::vector<WorldShape> walls;
  std::vector<WorldShape> obstacles;
  std::vector<Mark> marks;
  std::vector<Surface> surfaces;
};

/// Parses world YAML text; `source` names the file in error messages. The result is validated
/// (validate_world).
World parse_world_yaml(const std::string& text, const std::string& source = "<string>");
/// Reads a world YAML file.
World load_world_file(const std::string& path);

/// Checks what the types cannot: unique names, positive sizes, marks and surfaces entirely on an
/// existing wall face without overlapping each other, known ArUco dictionaries and ids, holes
/// shallower than their layer, paths with waypoints and a positive speed. Throws WorldError
/// "<where>: <field>: <why>", e.g. "world file 'site.yaml': marks[1].id: ...".
void validate_world(const World& world, const std::string& where);

/// "+x", "-x", "+y", "-y".
std::string to_string(Face face);

}  // namespace concert::world
