#pragma once
// A drilling mission: the areas to drill, in order, and how each is found (paper section 5.4).
// Plain C++, no DDS.

#include <Eigen/Core>
#include <Eigen/Geometry>

#include <filesystem>
#include <optional>
#include <stdexcept>
#include <string>
#include <vector>

namespace concert::drill {

/// Bad mission files, pattern tables, requests. The message names what is wrong and where,
/// e.g. "mission 'site.yaml': areas[2].wall: ...".
class DrillError : public std::runtime_error {
 public:
  using std::runtime_error::runtime_error;
};

/// What marks the user drew in an area.
enum class MarkKind {
  kBlobs,  ///< blue blobs: one hole per blob, drilled with visual servoing
  kAruco,  ///< an ArUco marker whose id selects a hole pattern: drilled on kinematics alone
};

/// Where an area is, as the user gave it (exactly one of wall, point, pixel).
struct AreaSpec {
  std::string name;  ///< unique in the mission ("area 1" if the file names none)
  MarkKind marks{MarkKind::kBlobs};
  /// (a) A wall of the BIM model: its IFC GlobalId, and the area centre at `at` = [s along the
  /// wall's axis from its start, h above the storey's elevation] [m]. The base navigates to the
  /// pose wall_goal() gives before the approach.
  std::string wall;
  Eigen::Vector2d at{0.0, 0.0};
  /// Which face of the wall: "left" or "right" of its axis (as `concert bim goal --face` shows
  /// them), or "auto" (wall_goal's choice: the face in the larger free region).
  std::string face{"auto"};
  /// (b) A point on the wall in the world (map) frame [m]; the normal comes from the point cloud.
  std::optional<Eigen::Vector3d> point;
  /// (c) A pixel [u, v] of the drill camera's current image; the point is where its depth ray
  /// meets the wall, the normal from the point cloud.
  std::optional<Eigen::Vector2d> pixel;
  /// Holes expected in the area (0: as many as are found). More found than expected: the
  /// nearest to the area centre are drilled; fewer: the missing ones are reported.
  int expected{0};
};

/// A mission file (YAML):
///   name: east wall               # optional
///   ifc: path/to/house.ifc        # needed by wall areas (relative to the file)
///   storey: Erdgeschoss           # storey of the wall areas (default: the wall's own)
///   patterns: path/patterns.yaml  # ArUco hole patterns (default: the service's table)
///   depth: 0.05                   # hole depth [m] (default 0.05)
///   areas:
///     - {name: a1, marks: blobs, wall: "1$wmdwWPjDYuku_ghVkynE", at: [1.2, 1.1], face: right}
///     - {name: a2, marks: aruco, point: [2.0, 0.3, 1.2]}
///     - {name: a3, marks: blobs, pixel: [320, 240], expected: 2}
struct Mission {
  std::string name;
  std::filesystem::path ifc;       ///< empty if no area is on a BIM wall
  std::string storey;              ///< empty: each wall's own storey
  std::filesystem::path patterns;  ///< empty: the service's default table
  double depth{0.05};              ///< [m]
  std::vector<AreaSpec> areas;
};

/// Parses a mission; `source` names it in errors. Throws DrillError naming the field and why
/// (unknown keys, an area with none or two of wall/point/pixel, a wall area without `ifc`,
/// non-finite numbers, duplicate names, no areas, depth outside (0, 0.3] m).
Mission parse_mission(const std::string& yaml, const std::string& source,
                      const std::filesystem::path& base_dir = {});
/// Reads and parses a mission file (relative paths in it are relative to the file).
Mission load_mission(const std::filesystem::path& file);

}  // namespace concert::drill
