// Frames, pixels, points and the per-pixel depth averaging.
#include <algorithm>
#include <cmath>
#include <cstdio>
#include <limits>
#include <string>

#include "drill/perception.hpp"
#include "frame_access.hpp"

namespace concert::drill {

namespace detail {

void fail(const hardware::RgbdFrame& frame, const std::string& what) {
  throw DrillError(describe(frame) + ": " + what);
}

double median(std::vector<double>& values) {
  if (values.empty()) {
    return 0.0;
  }
  const auto mid = values.begin() + static_cast<std::ptrdiff_t>(values.size() / 2);
  std::nth_element(values.begin(), mid, values.end());
  if (values.size() % 2 == 1) {
    return *mid;
  }
  return 0.5 * (*mid + *std::max_element(values.begin(), mid));
}

double interquartile_mean(std::vector<double>& values) {
  if (values.empty()) {
    return 0.0;
  }
  std::sort(values.begin(), values.end());
  const std::size_t n = values.size();
  const std::size_t first = n < 4 ? 0 : n / 4;
  const std::size_t last = n < 4 ? n : n - n / 4;
  double sum = 0.0;
  for (std::size_t i = first; i < last; ++i) {
    sum += values[i];
  }
  return sum / static_cast<double>(last - first);
}

}  // namespace detail

std::string describe(const hardware::RgbdFrame& frame) {
  char stamp[32];
  std::snprintf(stamp, sizeof(stamp), "%.3f", frame.stamp);
  return "rgbd frame '" + (frame.sensor.empty() ? std::string("?") : frame.sensor) +
         "' at t = " + stamp + " s";
}

void check_frame(const hardware::RgbdFrame& frame) {
  const auto& k = frame.intrinsics;
  if (k.width == 0 || k.height == 0) {
    detail::fail(frame, "empty image (" + std::to_string(k.width) + " x " +
                            std::to_string(k.height) + " px)");
  }
  const std::size_t pixels = static_cast<std::size_t>(k.width) * k.height;
  const std::string size = std::to_string(k.width) + " x " + std::to_string(k.height);
  if (frame.rgb.size() != 3 * pixels) {
    detail::fail(frame, "rgb has " + std::to_string(frame.rgb.size()) + " values, expected " +
                            std::to_string(3 * pixels) + " (" + size + " x 3)");
  }
  if (frame.depth.size() != pixels) {
    detail::fail(frame, "depth has " + std::to_string(frame.depth.size()) + " values, expected " +
                            std::to_string(pixels) + " (" + size + ")");
  }
  const auto positive = [](double v) { return std::isfinite(v) && v > 0.0; };
  if (!positive(k.fx) || !positive(k.fy) || !std::isfinite(k.cx) || !std::isfinite(k.cy)) {
    detail::fail(frame, "bad intrinsics (fx " + std::to_string(k.fx) + ", fy " +
                            std::to_string(k.fy) + " px: must be > 0; cx, cy finite)");
  }
  if (!positive(frame.depth_scale)) {
    detail::fail(frame, "depth_scale " + std::to_string(frame.depth_scale) + " must be > 0");
  }
}

Eigen::Vector3d deproject(const hardware::CameraIntrinsics& k, const Eigen::Vector2d& pixel,
                          double depth) {
  return {(pixel.x() - k.cx) / k.fx * depth, (pixel.y() - k.cy) / k.fy * depth, depth};
}

Eigen::Vector2d project(const hardware::CameraIntrinsics& k, const Eigen::Vector3d& point) {
  return {k.fx * point.x() / point.z() + k.cx, k.fy * point.y() / point.z() + k.cy};
}

Eigen::Vector3d point_at_pixel(const hardware::RgbdFrame& frame, const Eigen::Vector2d& pixel,
                               double radius) {
  check_frame(frame);
  char where[64];
  std::snprintf(where, sizeof(where), "pixel (%.1f, %.1f)", pixel.x(), pixel.y());
  const int u0 = static_cast<int>(std::lround(pixel.x()));
  const int v0 = static_cast<int>(std::lround(pixel.y()));
  if (!pixel.allFinite() || !detail::in_image(frame, u0, v0)) {
    detail::fail(frame, std::string(where) + " is outside the " +
                            std::to_string(frame.intrinsics.width) + " x " +
                            std::to_string(frame.intrinsics.height) + " image");
  }
  const int r = static_cast<int>(std::ceil(std::max(radius, 0.0)));
  std::vector<double> depths;
  for (int v = v0 - r; v <= v0 + r; ++v) {
    for (int u = u0 - r; u <= u0 + r; ++u) {
      const double du = u - pixel.x(), dv = v - pixel.y();
      if (!detail::in_image(frame, u, v) || (r > 0 && du * du + dv * dv > radius * radius)) {
        continue;
      }
      if (const double z = detail::depth_at(frame, u, v); z > 0.0) {
        depths.push_back(z);
      }
    }
  }
  if (depths.empty()) {
    char within[48];
    std::snprintf(within, sizeof(within), " within %.1f px", radius);
    detail::fail(frame, "no depth at " + std::string(where) + (r > 0 ? within : ""));
  }
  return deproject(frame.intrinsics, pixel, detail::median(depths));
}

DepthAverager::DepthAverager(std::size_t window, double min_valid)
    : window_(window), min_valid_(min_valid) {
  if (window == 0 || window > std::numeric_limits<std::uint16_t>::max()) {
    throw DrillError("depth averager: window " + std::to_string(window) +
                     " must be 1..65535 frames");
  }
  if (!(min_valid > 0.0 && min_valid <= 1.0)) {
    throw DrillError("depth averager: min_valid " + std::to_string(min_valid) +
                     " must be within (0, 1]");
  }
}

void DepthAverager::add(const hardware::RgbdFrame& frame) {
  check_frame(frame);
  if (!frames_.empty() && !(frame.intrinsics == latest_.intrinsics)) {
    detail::fail(frame, "its intrinsics (" + std::to_string(frame.intrinsics.width) + " x " +
                            std::to_string(frame.intrinsics.height) +
                            ") differ from the frames being averaged (" + describe(latest_) +
                            "): clear() first");
  }
  const std::size_t pixels = frame.depth.size();
  if (frames_.empty()) {
    sum_.assign(pixels, 0.0);
    count_.assign(pixels, 0);
  }
  std::vector<float> depth(pixels);
  for (std::size_t i = 0; i < pixels; ++i) {
    depth[i] = static_cast<float>(frame.depth_scale * frame.depth[i]);
  }
  if (frames_.size() == window_) {
    const std::vector<float>& oldest = frames_.front();
    for (std::size_t i = 0; i < pixels; ++i) {
      if (oldest[i] > 0.0f) {
        sum_[i] -= oldest[i];
        --count_[i];
      }
    }
    frames_.erase(frames_.begin());
  }
  for (std::size_t i = 0; i < pixels; ++i) {
    if (depth[i] > 0.0f) {
      sum_[i] += depth[i];
      ++count_[i];
    }
  }
  frames_.push_back(std::move(depth));
  latest_ = frame;
}

void DepthAverager::clear() {
  frames_.clear();
  sum_.clear();
  count_.clear();
}

hardware::RgbdFrame DepthAverager::average() const {
  if (frames_.empty()) {
    throw DrillError("depth averager: no frame to average yet");
  }
  hardware::RgbdFrame out = latest_;
  const double needed = min_valid_ * static_cast<double>(frames_.size());
  std::vector<double> mean(sum_.size(), 0.0);
  double farthest = 0.0;
  for (std::size_t i = 0; i < sum_.size(); ++i) {
    if (count_[i] > 0 && static_cast<double>(count_[i]) >= needed - 1e-9) {
      mean[i] = sum_[i] / count_[i];
      farthest = std::max(farthest, mean[i]);
    }
  }
  constexpr double kFine = 1e-4;  // [m] per step
  const double steps = std::numeric_limits<std::uint16_t>::max();
  out.depth_scale = std::max(kFine, farthest / steps);
  for (std::size_t i = 0; i < mean.size(); ++i) {
    out.depth[i] =
        static_cast<std::uint16_t>(std::min(steps, std::round(mean[i] / out.depth_scale)));
  }
  return out;
}

}  // namespace concert::drill
