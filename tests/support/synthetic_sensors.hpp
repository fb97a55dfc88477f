#pragma once
// Test helper: sensor data with every field set from a seed (libs/hardware types), so that
// tests and benchmarks of the sensor topics compare what they wrote with what they read.
// Header-only; users link concert_hardware.

#include <cmath>
#include <cstdint>
#include <random>
#include <string>

#include "concert/hardware/sensors.hpp"

namespace concert::testing {

/// An RGB-D frame of `width` x `height` px with seeded pixel values (every depth value in
/// 1..65535 mm, so none reads as "no data" by accident), intrinsics of a 69 deg camera.
inline hardware::RgbdFrame synthetic_rgbd_frame(const std::string& sensor, uint32_t width,
                                                uint32_t height, uint32_t seed,
                                                double stamp = 12.5) {
  std::mt19937 rng(seed);
  std::uniform_int_distribution<int> byte(0, 255);
  std::uniform_int_distribution<int> mm(1, 65535);
  hardware::RgbdFrame f;
  f.sensor = sensor;
  f.frame = sensor + "_optical";
  f.stamp = stamp;
  const double focal = 0.5 * width / std::tan(0.5 * 69.0 * M_PI / 180.0);
  f.intrinsics = {
      width, height, focal, focal + 0.25, 0.5 * (width - 1), 0.5 * (height - 1) + 0.125};
  f.rgb.resize(static_cast<size_t>(width) * height * 3);
  for (auto& b : f.rgb) b = static_cast<uint8_t>(byte(rng));
  f.depth.resize(static_cast<size_t>(width) * height);
  for (auto& d : f.depth) d = static_cast<uint16_t>(mm(rng));
  f.depth_scale = 0.001;
  f.depth_min = 0.28f;
  f.depth_max = 6.0f;
  return f;
}

/// A 3D lidar revolution of `rings` x `columns` with seeded ranges.
inline hardware::LidarScan synthetic_lidar_scan(const std::string& sensor, uint32_t rings,
                                                uint32_t columns, uint32_t seed) {
  std::mt19937 rng(seed);
  std::uniform_real_distribution<float> range(0.5f, 90.0f);
  hardware::LidarScan s;
  s.sensor = sensor;
  s.frame = sensor + "_link";
  s.stamp = 3.25;
  for (uint32_t r = 0; r < rings; ++r)
    s.elevations.push_back(-0.26f + 0.035f * static_cast<float>(r));
  s.azimuth_min = -M_PI;
  s.azimuth_increment = 2.0 * M_PI / columns;
  s.columns = columns;
  s.ranges.resize(static_cast<size_t>(rings) * columns);
  for (auto& x : s.ranges) x = range(rng);
  s.range_min = 0.4f;
  s.range_max = 100.0f;
  return s;
}

}  // namespace concert::testing
