// Blue blobs: HSV segmentation, outer contours, circularity and metric size, depth behind them.
#include <algorithm>
#include <cmath>
#include <opencv2/imgproc.hpp>

#include "drill/perception.hpp"
#include "frame_access.hpp"

namespace concert::drill {

namespace {

/// The pixels of `params`' blue, opened by a 3 x 3 ellipse (single-pixel specks go).
cv::Mat blue_mask(const hardware::RgbdFrame& frame, const BlobParams& params) {
  const auto& k = frame.intrinsics;
  const cv::Mat rgb(static_cast<int>(k.height), static_cast<int>(k.width), CV_8UC3,
                    const_cast<std::uint8_t*>(frame.rgb.data()));
  cv::Mat hsv;
  cv::cvtColor(rgb, hsv, cv::COLOR_RGB2HSV);
  cv::Mat mask;
  cv::inRange(hsv, cv::Scalar(params.hue_min, params.saturation_min, params.value_min),
              cv::Scalar(params.hue_max, 255, 255), mask);
  cv::morphologyEx(mask, mask, cv::MORPH_OPEN,
                   cv::getStructuringElement(cv::MORPH_ELLIPSE, cv::Size(3, 3)));
  return mask;
}

bool touches_border(const cv::Rect& box, const hardware::CameraIntrinsics& k, int margin) {
  return box.x < margin || box.y < margin ||
         box.x + box.width > static_cast<int>(k.width) - margin ||
         box.y + box.height > static_cast<int>(k.height) - margin;
}

}  // namespace

std::vector<Blob> detect_blobs(const hardware::RgbdFrame& frame, const BlobParams& params) {
  check_frame(frame);
  const auto& k = frame.intrinsics;
  const cv::Mat mask = blue_mask(frame, params);
  std::vector<std::vector<cv::Point>> contours;
  cv::findContours(mask, contours, cv::RETR_EXTERNAL, cv::CHAIN_APPROX_NONE);
  const double focal = 0.5 * (k.fx + k.fy);
  std::vector<Blob> blobs;
  std::vector<double> depths;
  for (const auto& contour : contours) {
    const cv::Rect box = cv::boundingRect(contour);
    if (touches_border(box, k, params.border_px)) {
      continue;
    }
    const double perimeter = cv::arcLength(contour, true);
    const double outline_area = cv::contourArea(contour);
    if (perimeter <= 0.0 || outline_area <= 0.0) {
      continue;
    }
    Blob blob;
    blob.circularity = 4.0 * M_PI * outline_area / (perimeter * perimeter);
    if (blob.circularity < params.min_circularity) {
      continue;
    }
    // The region: the outline filled (a highlight or a dirty spot inside still counts).
    cv::Mat region = cv::Mat::zeros(box.size(), CV_8U);
    cv::drawContours(region, std::vector<std::vector<cv::Point>>{contour}, 0, cv::Scalar(255),
                     cv::FILLED, cv::LINE_8, cv::noArray(), 0, -box.tl());
    const cv::Moments m = cv::moments(region, true);
    if (m.m00 <= 0.0) {
      continue;
    }
    blob.pixel = {box.x + m.m10 / m.m00, box.y + m.m01 / m.m00};
    // A uniform disc of radius r has variance r^2 / 4 along every axis; seen at an angle it is
    // an ellipse whose major axis keeps the radius.
    const double a = m.mu20 / m.m00, b = m.mu02 / m.m00, c = m.mu11 / m.m00;
    const double major = 0.5 * (a + b) + std::sqrt(0.25 * (a - b) * (a - b) + c * c);
    blob.radius_px = 2.0 * std::sqrt(major);
    if (blob.radius_px < params.min_radius_px) {
      continue;
    }
    depths.clear();
    for (int v = 0; v < region.rows; ++v) {
      for (int u = 0; u < region.cols; ++u) {
        if (region.at<std::uint8_t>(v, u) != 0) {
          if (const double z = detail::depth_at(frame, box.x + u, box.y + v); z > 0.0) {
            depths.push_back(z);
          }
        }
      }
    }
    blob.depth_samples = static_cast<int>(depths.size());
    if (depths.empty()) {
      continue;
    }
    const double z = detail::interquartile_mean(depths);
    blob.position = deproject(k, blob.pixel, z);
    blob.diameter = 2.0 * blob.radius_px * z / focal;
    if (blob.diameter < params.min_diameter || blob.diameter > params.max_diameter) {
      continue;
    }
    blobs.push_back(blob);
  }
  std::sort(blobs.begin(), blobs.end(),
            [](const Blob& x, const Blob& y) { return x.radius_px > y.radius_px; });
  return blobs;
}

}  // namespace concert::drill
