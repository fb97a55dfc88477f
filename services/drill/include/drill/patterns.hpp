#pragma once
// Hole patterns encoded by ArUco markers (paper section 5.4.3: "the robot automatically sets the
// drilling point frames following a pattern associated with the Aruco's id"). Plain C++, no DDS.
//
// Marker frame (detect_aruco, perception.hpp): origin at the marker's centre on its front
// surface, z out of the marker towards the viewer, x the marker's right, y its up, as printed
// (the upright marker's top-left corner is at (-s/2, s/2, 0)). A pattern is a row of `count`
// holes `spacing` apart along `direction`, centred at `centre`, all in the marker's plane.

#include <Eigen/Core>
#include <Eigen/Geometry>
#include <filesystem>
#include <string>
#include <vector>

namespace concert::drill {

/// One marker id's holes.
struct HolePattern {
  int id{0};                         ///< marker id in the table's dictionary
  Eigen::Vector2d centre{0.0, 0.0};  ///< row centre [x, y] in the marker frame [m]
  double direction{0.0};             ///< row direction about marker z from its x [rad]
  int count{1};                      ///< holes in the row, >= 1
  double spacing{0.0};               ///< between neighbouring holes [m], > 0 if count > 1
};

/// The patterns of one set of printed markers.
class PatternTable {
 public:
  PatternTable() = default;
  /// Throws DrillError naming `source` and the offending entry if two patterns share an id.
  PatternTable(std::string source, std::string dictionary, double marker_size,
               std::vector<HolePattern> patterns);

  /// The pattern of marker `id`, or nullptr if the table has none.
  [[nodiscard]] const HolePattern* find(int id) const;
  [[nodiscard]] const std::vector<HolePattern>& patterns() const { return patterns_; }
  /// OpenCV predefined dictionary the markers are from, e.g. "DICT_4X4_50".
  [[nodiscard]] const std::string& dictionary() const { return dictionary_; }
  /// Printed marker side, black border included (OpenCV markerLength) [m].
  [[nodiscard]] double marker_size() const { return marker_size_; }
  /// Where the table came from (the file, or the name given to parse_patterns).
  [[nodiscard]] const std::string& source() const { return source_; }

 private:
  std::string source_;
  std::string dictionary_{"DICT_4X4_50"};
  double marker_size_{0.1};
  std::vector<HolePattern> patterns_;
};

/// Parses a pattern table (YAML); `source` names it in errors:
///   dictionary: DICT_4X4_50   # OpenCV predefined dictionary of the printed markers
///   marker_size: 0.1          # printed side, border included [m]
///   patterns:                 # a map from marker id to its row
///     0: {centre: [0.0, -0.15], direction: 0.0, count: 4, spacing: 0.2}
/// Throws DrillError "patterns '<source>': patterns[3].spacing: must be > 0 (got -0.1)" for
/// unknown keys, missing or non-finite fields, an unknown dictionary, ids outside it or twice,
/// count < 1, spacing <= 0 with count > 1, marker_size <= 0.
PatternTable parse_patterns(const std::string& yaml, const std::string& source);
/// Reads and parses a pattern file; throws DrillError naming the file if it cannot be read.
PatternTable load_patterns(const std::filesystem::path& path);

/// The holes of `pattern` for a marker at `world_T_marker` (any parent frame: optical, world):
/// hole i of n at centre + (i - (n - 1) / 2) * spacing * (cos direction, sin direction) in the
/// marker's xy plane, oriented as the marker (z = marker z, the surface's outward normal), in
/// order along `direction`.
std::vector<Eigen::Isometry3d> pattern_holes(const Eigen::Isometry3d& world_T_marker,
                                             const HolePattern& pattern);

}  // namespace concert::drill
