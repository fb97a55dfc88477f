#pragma once
// Camera images as compressed frames for the browser (OpenCV's JPEG encoder).

#include <cstddef>
#include <cstdint>
#include <optional>
#include <string>
#include <string_view>

namespace concert::gui {

/// An image as the sensor topics carry it (idl/sensors.idl Image): rows top first.
struct ImageView {
  std::string_view encoding;  ///< "rgb8" or "16UC1"
  uint32_t width = 0;         ///< [px]
  uint32_t height = 0;        ///< [px]
  uint32_t step = 0;          ///< [bytes] per row
  double depth_scale = 0.0;   ///< [m] per depth unit (16UC1)
  const uint8_t* data = nullptr;
  size_t size = 0;            ///< [bytes]
};

struct JpegParams {
  int quality = 70;          ///< 0..100
  double depth_max_m = 4.0;  ///< depth shown white at 0 m fading to black at this range
};

/// The image as JPEG bytes; colour as is, depth as grey levels (near bright, no depth black).
/// nullopt with `error` set for an encoding it does not know or a size that does not fit.
std::optional<std::string> encode_jpeg(const ImageView& image, const JpegParams& params, std::string& error);

}  // namespace concert::gui
