#pragma once
// The robot's collision primitives (boxes, cylinders, spheres of libs/model) as FCL objects,
// placed at the links' poses. One implementation of the self-collision check for every service
// that judges a posture (the planner's state checker, surface_finish's reach), so that the two
// agree on which postures collide.
//
// Self collision is checked between links that move against each other: links in different
// rigid groups (rigid_groups()), less the pairs the model disables (its SRDF). Each shape also
// has a padded copy (every side grown by `padding`) for clearance checks against the world,
// which stay with their owners (the planner's octree, surface_finish's wall).

#include <fcl/fcl.h>

#include <Eigen/Geometry>
#include <map>
#include <memory>
#include <optional>
#include <string>
#include <utility>
#include <vector>

#include "concert/model/robot_model.hpp"

namespace concert::collision {

/// For each link of `model`: the index of the nearest link at or above it (itself included)
/// whose joint from its parent moves and is one of `joints`; -1 for the links that move with the
/// root. Links of one group never move against each other.
std::vector<int> rigid_groups(const model::RobotModel& model, const std::vector<std::string>& joints);

/// One primitive of a link.
struct Shape {
  int link = -1;                     ///< index in the model's links
  model::CollisionShape primitive;   ///< box, cylinder or sphere, in the link frame
  double bounding_radius = 0.0;      ///< of the exact shape, about its origin [m]
  double padded_radius = 0.0;        ///< of the padded shape, about the padded object's origin [m]
};

class LinkShapes {
 public:
  /// The primitives of every link of `model` (mesh shapes are skipped and named in ignored());
  /// self-collision pairs between links whose `groups` differ (one entry per link, e.g.
  /// rigid_groups()) and whose pair the model does not disable. `padding` >= 0 [m]. `extra`:
  /// primitives a link has beyond the model's (by link index; a drill's bit, which the module
  /// database does not describe). An extra cylinder is a bit whose tip is its +z end: padded
  /// sideways and backwards, not beyond the tip.
  LinkShapes(const model::RobotModel& model, const std::vector<int>& groups, double padding = 0.0,
             const std::map<int, std::vector<model::CollisionShape>>& extra = {});
  ~LinkShapes();
  LinkShapes(LinkShapes&&) noexcept;
  LinkShapes& operator=(LinkShapes&&) noexcept;

  /// Places every shape at its link's pose (`link_poses[link]`, one per link of the model;
  /// links without shapes are not read).
  void place(const std::vector<Eigen::Isometry3d>& link_poses);
  /// The first pair of links (lower index first) whose exact shapes touch where they were last
  /// placed, or nullopt.
  [[nodiscard]] std::optional<std::pair<int, int>> self_collision() const;

  [[nodiscard]] const std::vector<Shape>& shapes() const;
  /// The exact and the padded FCL object of shapes()[i], where last placed (AABB computed).
  [[nodiscard]] const fcl::CollisionObjectd& exact(std::size_t i) const;
  [[nodiscard]] const fcl::CollisionObjectd& padded(std::size_t i) const;
  /// Links with at least one shape, in link order.
  [[nodiscard]] const std::vector<int>& links_with_shapes() const;
  /// The pairs of shapes (indices into shapes()) checked for self collision.
  [[nodiscard]] const std::vector<std::pair<int, int>>& pairs() const;
  /// "link: mesh" for every mesh shape left out (primitives only).
  [[nodiscard]] const std::vector<std::string>& ignored() const;
  [[nodiscard]] double padding() const;

 private:
  struct Impl;
  std::unique_ptr<Impl> impl_;
};

}  // namespace concert::collision
