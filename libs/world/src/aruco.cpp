#include "concert/world/aruco.hpp"

#include <algorithm>
#include <opencv2/aruco.hpp>

#include "concert/world/world.hpp"

namespace concert::world {
namespace {

// In the order of cv::aruco::PREDEFINED_DICTIONARY_NAME (OpenCV 4.6): the index is the enum value.
const std::vector<std::string> kNames{
    "DICT_4X4_50",         "DICT_4X4_100",       "DICT_4X4_250",       "DICT_4X4_1000",
    "DICT_5X5_50",         "DICT_5X5_100",       "DICT_5X5_250",       "DICT_5X5_1000",
    "DICT_6X6_50",         "DICT_6X6_100",       "DICT_6X6_250",       "DICT_6X6_1000",
    "DICT_7X7_50",         "DICT_7X7_100",       "DICT_7X7_250",       "DICT_7X7_1000",
    "DICT_ARUCO_ORIGINAL", "DICT_APRILTAG_16h5", "DICT_APRILTAG_25h9", "DICT_APRILTAG_36h10",
    "DICT_APRILTAG_36h11"};
static_assert(cv::aruco::DICT_APRILTAG_36h11 == 20, "dictionary names follow OpenCV's enum");

cv::Ptr<cv::aruco::Dictionary> dictionary(const std::string& name) {
  const auto it = std::find(kNames.begin(), kNames.end(), name);
  if (it == kNames.end()) {
    std::string all;
    for (const auto& n : kNames) {
      all += (all.empty() ? "" : ", ") + n;
    }
    throw WorldError("unknown ArUco dictionary '" + name + "' (accepted: " + all + ")");
  }
  return cv::aruco::getPredefinedDictionary(static_cast<int>(it - kNames.begin()));
}

}  // namespace

const std::vector<std::string>& aruco_dictionary_names() { return kNames; }

bool is_aruco_dictionary(const std::string& name) {
  return std::find(kNames.begin(), kNames.end(), name) != kNames.end();
}

int aruco_dictionary_size(const std::string& name) { return dictionary(name)->bytesList.rows; }

ArucoCells aruco_cells(const std::string& name, int id) {
  const auto dict = dictionary(name);
  if (id < 0 || id >= dict->bytesList.rows) {
    throw WorldError("ArUco id " + std::to_string(id) + " is not in " + name + " (ids 0.." +
                     std::to_string(dict->bytesList.rows - 1) + ")");
  }
  // The same bits cv::aruco::drawMarker draws inside its black border (rotation 0).
  const cv::Mat bits = cv::aruco::Dictionary::getBitsFromByteList(
      dict->bytesList.rowRange(id, id + 1), dict->markerSize);
  ArucoCells cells;
  cells.side = dict->markerSize + 2;
  cells.white.assign(static_cast<std::size_t>(cells.side * cells.side), false);
  for (int r = 0; r < dict->markerSize; ++r) {
    for (int c = 0; c < dict->markerSize; ++c) {
      cells.white[static_cast<std::size_t>((r + 1) * cells.side + c + 1)] =
          bits.at<unsigned char>(r, c) != 0;
    }
  }
  return cells;
}

}  // namespace concert::world
