#pragma once

#include <Eigen/Core>
#include <cstdint>
#include <stdexcept>
#include <string>
#include <vector>

namespace concert::bim {

/// Bad map file or grid argument (names the file and what is wrong).
class MapError : public std::runtime_error {
 public:
  using std::runtime_error::runtime_error;
};

/// A 2D occupancy grid in the map frame, laid out as nav2's map_server reads it:
/// cell (col, row) covers [origin.x + col * resolution, + resolution) x
/// [origin.y + row * resolution, + resolution); row 0 is the bottom row (smallest y).
/// Cells hold kFree, kOccupied or kUnknown.
struct OccupancyGrid {
  static constexpr std::int8_t kFree = 0;
  static constexpr std::int8_t kOccupied = 100;
  static constexpr std::int8_t kUnknown = -1;

  int width{0};             ///< columns (x)
  int height{0};            ///< rows (y)
  double resolution{0.05};  ///< cell side [m]
  Eigen::Vector2d origin{0.0,
                         0.0};  ///< map-frame position of the lower-left corner of cell (0, 0) [m]
  std::vector<std::int8_t> cells;  ///< row-major, width * height, row 0 at the bottom

  /// An all-`fill` grid. Throws MapError unless width, height > 0 and resolution > 0.
  static OccupancyGrid filled(int width, int height, double resolution,
                              const Eigen::Vector2d& origin, std::int8_t fill = kFree);

  [[nodiscard]] bool inside(int col, int row) const {
    return col >= 0 && row >= 0 && col < width && row < height;
  }
  [[nodiscard]] std::size_t index(int col, int row) const {
    return static_cast<std::size_t>(row) * static_cast<std::size_t>(width) +
           static_cast<std::size_t>(col);
  }
  [[nodiscard]] std::int8_t at(int col, int row) const { return cells[index(col, row)]; }
  std::int8_t& at(int col, int row) { return cells[index(col, row)]; }
  /// Cell containing a map-frame point (may be outside the grid: check inside()).
  [[nodiscard]] Eigen::Vector2i cell_of(const Eigen::Vector2d& p) const;
  /// Map-frame centre of a cell [m].
  [[nodiscard]] Eigen::Vector2d center_of(int col, int row) const;
  /// True when the point lies in an occupied cell; points outside the grid count as occupied.
  [[nodiscard]] bool occupied(const Eigen::Vector2d& p) const;
};

/// Map metadata of nav2's map_server YAML (map.yaml).
struct MapMetadata {
  std::string image;                ///< image file, relative to the YAML file's folder
  double resolution{0.05};          ///< [m/cell]
  Eigen::Vector3d origin{0, 0, 0};  ///< x, y [m], yaw [rad] of the image's lower-left pixel
  bool negate{false};
  double occupied_thresh{0.65};
  double free_thresh{0.25};
  std::string mode{"trinary"};
};

/// Writes `grid` as nav2 map_server files: `<dir>/<stem>.pgm` (binary P5, 8 bit: occupied 0,
/// free 254, unknown 205, top row first) and `<dir>/<stem>.yaml` (image, resolution, origin,
/// negate 0, occupied_thresh 0.65, free_thresh 0.196 (ROS map_saver's value: unknown 205 reads back
/// as unknown, with 0.25 it would read as free), mode trinary). Creates `dir`.
/// Throws MapError naming the file on a write failure.
void save_map(const OccupancyGrid& grid, const std::string& dir, const std::string& stem = "map");

/// Reads a nav2 map_server YAML and its PGM image (P5 or P2; trinary thresholds applied as
/// map_server does, with `negate`). Throws MapError naming the file and the field on bad input.
OccupancyGrid load_map(const std::string& yaml_path);

}  // namespace concert::bim
