#pragma once
// ArUco dictionaries as the world knows them (OpenCV's predefined dictionaries, from OpenCV).

#include <string>
#include <vector>

namespace concert::world {

/// Names of OpenCV 4.6's predefined dictionaries (DICT_4X4_50 ... DICT_APRILTAG_36h11).
const std::vector<std::string>& aruco_dictionary_names();

/// True if `name` is a predefined dictionary.
bool is_aruco_dictionary(const std::string& name);

/// Number of markers in a dictionary (ids are 0 .. size-1); throws WorldError if unknown.
int aruco_dictionary_size(const std::string& name);

/// The cells of marker `id` as OpenCV draws it (cv::aruco::drawMarker with a 1-cell border):
/// (bits + 2)^2 cells, row-major, row 0 at the top, column 0 at the left, seen from the front of
/// the upright marker; true = white. Throws WorldError for an unknown dictionary or id.
struct ArucoCells {
  int side{0};              ///< cells per side, border included
  std::vector<bool> white;  ///< side * side
  [[nodiscard]] bool at(int row, int col) const {
    return white[static_cast<std::size_t>(row * side + col)];
  }
};
ArucoCells aruco_cells(const std::string& dictionary, int id);

}  // namespace concert::world
