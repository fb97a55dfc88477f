#pragma once

#include <Eigen/Core>
#include <array>
#include <string>
#include <vector>

#include "concert/bim/model.hpp"

namespace concert::bim {

/// A rectangle in the xy plane: the smallest-area one around an element's projected mesh.
struct OrientedBox2 {
  Eigen::Vector2d center{0, 0};  ///< [m]
  Eigen::Vector2d half{0, 0};    ///< half extents along the box's own x and y axes [m], x >= y
  double yaw{0.0};               ///< direction of the box's x axis from world x [rad]
  /// Corners counter-clockwise, from (-half.x, -half.y) [m].
  [[nodiscard]] std::array<Eigen::Vector2d, 4> corners() const;
};

/// One vertical face of a wall: the line on the face beside the wall's axis.
struct WallFace {
  Eigen::Vector2d normal{0, 0};  ///< unit outward normal (horizontal)
  Eigen::Vector2d start{0, 0};   ///< point on the face beside the axis start [m]
  Eigen::Vector2d end{0, 0};     ///< point on the face beside the axis end [m]
};

/// A wall as a straight slab: its axis, thickness, z range and two faces, from the oriented box
/// of its footprint. The axis runs along the box's long side, in the direction of the wall's IFC
/// placement x axis (the direction the authoring tool drew it), through the box's middle.
/// Curved or L-shaped walls are approximated by their box.
struct WallGeometry {
  Eigen::Vector2d start{0, 0};  ///< [m]
  Eigen::Vector2d end{0, 0};    ///< [m]
  double thickness{0.0};        ///< [m]
  double z_min{0.0};            ///< [m] world
  double z_max{0.0};            ///< [m] world
  /// faces[0]: left of the axis (normal = axis direction turned +90 deg about z); faces[1]: right.
  std::array<WallFace, 2> faces;
  [[nodiscard]] double length() const { return (end - start).norm(); }
  [[nodiscard]] Eigen::Vector2d direction() const { return (end - start).normalized(); }
};

/// The smallest-area rectangle around the element's mesh projected to xy. Throws BimError when
/// the element has no mesh.
OrientedBox2 footprint(const Element& element);

/// The wall's axis, thickness and faces. Throws BimError naming the element when it is not a
/// wall or has no mesh.
WallGeometry wall_geometry(const Element& wall);

/// geometry.json of a storey (README "geometry.json"): the storey, then every wall, door,
/// window, column and slab assigned to it with GlobalId, IFC type, name, footprint (oriented
/// box and its corners) and z range; walls with axis, thickness and faces; doors and windows
/// with their host wall.
std::string geometry_json(const BimModel& model, const Storey& storey);

}  // namespace concert::bim
