#include "gui/image.hpp"

#include <opencv2/core.hpp>
#include <opencv2/imgcodecs.hpp>
#include <opencv2/imgproc.hpp>
#include <vector>

namespace concert::gui {

std::optional<std::string> encode_jpeg(const ImageView& image, const JpegParams& params, std::string& error) {
  const bool colour = image.encoding == "rgb8";
  const bool depth = image.encoding == "16UC1";
  if (!colour && !depth) {
    error = "image encoding '" + std::string(image.encoding) + "' is not rgb8 or 16UC1";
    return std::nullopt;
  }
  const size_t pixel = colour ? 3 : 2;
  if (image.width == 0 || image.height == 0 || image.step < image.width * pixel ||
      image.size < static_cast<size_t>(image.step) * image.height || image.data == nullptr) {
    error = "image " + std::to_string(image.width) + "x" + std::to_string(image.height) + " step " +
            std::to_string(image.step) + " does not fit its " + std::to_string(image.size) + " bytes";
    return std::nullopt;
  }
  const int rows = static_cast<int>(image.height);
  const int cols = static_cast<int>(image.width);
  // OpenCV only reads through these headers (const_cast: cv::Mat has no const-data constructor).
  auto* data = const_cast<uint8_t*>(image.data);
  cv::Mat out;
  if (colour) {
    cv::cvtColor(cv::Mat(rows, cols, CV_8UC3, data, image.step), out, cv::COLOR_RGB2BGR);
  } else {
    const cv::Mat raw(rows, cols, CV_16UC1, data, image.step);
    const double scale = image.depth_scale > 0 ? image.depth_scale : 0.001;
    cv::Mat metres;
    raw.convertTo(metres, CV_32F, scale);
    out.create(rows, cols, CV_8UC1);
    for (int r = 0; r < rows; ++r) {
      const float* m = metres.ptr<float>(r);
      uint8_t* o = out.ptr<uint8_t>(r);
      for (int c = 0; c < cols; ++c) {
        const double v = m[c] <= 0 ? 0.0 : 255.0 * (1.0 - std::min(1.0, m[c] / params.depth_max_m));
        o[c] = static_cast<uint8_t>(v);
      }
    }
  }
  std::vector<uchar> bytes;
  if (!cv::imencode(".jpg", out, bytes, {cv::IMWRITE_JPEG_QUALITY, params.quality})) {
    error = "the JPEG encoder failed";
    return std::nullopt;
  }
  return std::string(bytes.begin(), bytes.end());
}

}  // namespace concert::gui
