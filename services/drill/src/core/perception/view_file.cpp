// A camera view written to a file, for a person to look at.
#include <cmath>

#include <opencv2/imgcodecs.hpp>
#include <opencv2/imgproc.hpp>

#include "drill/perception.hpp"

namespace concert::drill {

void write_view_png(const hardware::RgbdFrame& frame, const std::string& path,
                    const std::optional<Eigen::Vector2d>& mark) {
  check_frame(frame);
  const cv::Mat rgb(static_cast<int>(frame.intrinsics.height), static_cast<int>(frame.intrinsics.width),
                    CV_8UC3, const_cast<std::uint8_t*>(frame.rgb.data()));
  cv::Mat bgr;
  cv::cvtColor(rgb, bgr, cv::COLOR_RGB2BGR);
  if (mark) {
    // Drawn where the mark was expected (clipped to the image by OpenCV when outside).
    const cv::Point at(static_cast<int>(std::lround(mark->x())), static_cast<int>(std::lround(mark->y())));
    const cv::Scalar red(0, 0, 255);
    cv::drawMarker(bgr, at, red, cv::MARKER_CROSS, 24, 2);
    cv::circle(bgr, at, 16, red, 2);
  }
  bool written = false;
  try {
    written = cv::imwrite(path, bgr);
  } catch (const cv::Exception& e) {
    throw DrillError("cannot write " + describe(frame) + " to '" + path + "': " + e.what());
  }
  if (!written) throw DrillError("cannot write " + describe(frame) + " to '" + path + "'");
}

}  // namespace concert::drill
