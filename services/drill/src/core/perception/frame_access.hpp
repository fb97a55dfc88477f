#pragma once
// What the perception sources share: reading a frame's pixels and robust averages.

#include <cstddef>
#include <string>
#include <vector>

#include "concert/hardware/sensors.hpp"
#include "drill/mission.hpp"

namespace concert::drill::detail {

/// Depth of pixel (u, v) [m]; 0 = no data. No bounds check (the frame passed check_frame).
inline double depth_at(const hardware::RgbdFrame& f, int u, int v) {
  return f.depth_scale *
         f.depth[static_cast<std::size_t>(v) * f.intrinsics.width + static_cast<std::size_t>(u)];
}

/// Whether pixel (u, v) lies in the image.
inline bool in_image(const hardware::RgbdFrame& f, int u, int v) {
  return u >= 0 && v >= 0 && u < static_cast<int>(f.intrinsics.width) &&
         v < static_cast<int>(f.intrinsics.height);
}

/// DrillError "<describe(frame)>: <what>".
[[noreturn]] void fail(const hardware::RgbdFrame& frame, const std::string& what);

/// Median of `values` (reordered); 0 for none.
double median(std::vector<double>& values);

/// Mean of the middle half of `values` (reordered; all of them if fewer than 4): as robust to
/// outliers as the median, and not quantised to the values' steps. 0 for none.
double interquartile_mean(std::vector<double>& values);

}  // namespace concert::drill::detail
