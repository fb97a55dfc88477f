#include "surface_finish/deposition.hpp"

#include <opencv2/core.hpp>
#include <opencv2/imgcodecs.hpp>
#include <opencv2/imgproc.hpp>

#include <algorithm>
#include <cmath>
#include <nlohmann/json.hpp>

namespace concert::surface_finish {

SprayDeposition::SprayDeposition(const WallFrame& wall, const Rect& rect, const ToolSpec& tool, double speed,
                                 int strokes, DepositionParams params)
    : wall_(wall), rect_(rect), tool_(tool), params_(params) {
  if (!(rect.width() > 0.0) || !(rect.height() > 0.0)) throw FinishError("deposition: rectangle " + rect.str() + " has no positive size");
  if (!(params.cell > 0.0) || !(params.margin >= 0.0) || !(params.visible > 0.0 && params.visible < 1.0)) {
    throw FinishError("deposition: cell > 0, margin >= 0 and 0 < visible < 1 needed");
  }
  if (tool.task != Task::kSpray || !(tool.standoff > 0.0) || !(tool.coat_width > 0.0)) {
    throw FinishError("deposition: a spraying tool with a positive standoff and coat width is needed");
  }
  if (!(speed > 0.0) || strokes < 1) throw FinishError("deposition: speed > 0 and at least one stroke needed");
  nx_ = static_cast<int>(std::ceil((rect.width() + 2.0 * params.margin) / params.cell));
  ny_ = static_cast<int>(std::ceil((rect.height() + 2.0 * params.margin) / params.cell));
  x0_ = rect.x0 - params.margin + 0.5 * params.cell;
  y0_ = rect.y0 - params.margin + 0.5 * params.cell;
  // Film of one pass at the standoff d and speed v on the centre line: integral of
  // d / (d^2 + u^2)^(3/2) du / v over the footprint |u| <= R = d tan(alpha).
  const double d = tool.standoff;
  const double r = d * std::tan(tool.cone_half_angle());
  nominal_ = 2.0 / speed * r / (d * std::sqrt(d * d + r * r));
  per_stroke_.assign(static_cast<std::size_t>(strokes), std::vector<float>(static_cast<std::size_t>(nx_ * ny_), 0.0f));
}

void SprayDeposition::add(const Eigen::Isometry3d& tcp, double dt, int stroke) {
  if (stroke < 0 || stroke >= static_cast<int>(per_stroke_.size()) || !(dt > 0.0)) return;
  const Eigen::Isometry3d in_wall = wall_.pose.inverse() * tcp;
  const Eigen::Vector3d p = in_wall.translation();
  const Eigen::Vector3d axis = in_wall.linear().col(2);
  if (p.z() <= 1e-4 || axis.z() >= -1e-3) return;  // behind the wall or spraying away from it
  const double alpha = tool_.cone_half_angle();
  const double cos_alpha = std::cos(alpha);
  const double tilt = std::acos(std::clamp(-axis.z(), -1.0, 1.0));
  if (tilt + alpha >= 1.4) return;
  // The cone's footprint lies within this radius of the axis' hit point.
  const double hit = p.z() / -axis.z();
  const Eigen::Vector3d centre = p + hit * axis;
  const double bound = 1.2 * p.z() * (std::tan(tilt + alpha) - std::tan(tilt - alpha)) + params_.cell;
  const int ix0 = std::max(0, static_cast<int>(std::floor((centre.x() - bound - x0_) / params_.cell)));
  const int ix1 = std::min(nx_ - 1, static_cast<int>(std::ceil((centre.x() + bound - x0_) / params_.cell)));
  const int iy0 = std::max(0, static_cast<int>(std::floor((centre.y() - bound - y0_) / params_.cell)));
  const int iy1 = std::min(ny_ - 1, static_cast<int>(std::ceil((centre.y() + bound - y0_) / params_.cell)));
  std::vector<float>& film = per_stroke_[static_cast<std::size_t>(stroke)];
  for (int iy = iy0; iy <= iy1; ++iy) {
    for (int ix = ix0; ix <= ix1; ++ix) {
      const Eigen::Vector3d ray(x0_ + ix * params_.cell - p.x(), y0_ + iy * params_.cell - p.y(), -p.z());
      const double dist = ray.norm();
      if (ray.dot(axis) < cos_alpha * dist) continue;
      const double cos_phi = p.z() / dist;
      film[static_cast<std::size_t>(iy * nx_ + ix)] += static_cast<float>(dt * cos_phi / (dist * dist) / nominal_);
    }
  }
}

double SprayDeposition::stroke_film(int s, int ix, int iy) const {
  return per_stroke_[static_cast<std::size_t>(s)][static_cast<std::size_t>(iy * nx_ + ix)];
}

double SprayDeposition::film(int ix, int iy) const {
  double f = 0.0;
  for (std::size_t s = 0; s < per_stroke_.size(); ++s) f += per_stroke_[s][static_cast<std::size_t>(iy * nx_ + ix)];
  return f;
}

SprayReport SprayDeposition::measure(const std::vector<double>& stroke_x, const std::vector<bool>& stroke_up) const {
  if (stroke_x.size() != per_stroke_.size() || stroke_up.size() != per_stroke_.size()) {
    throw FinishError("deposition: " + std::to_string(per_stroke_.size()) + " strokes recorded, " +
                      std::to_string(stroke_x.size()) + " positions given");
  }
  const double c = params_.cell;
  const double vis = params_.visible;
  // Where the film crosses the threshold between a painted cell at u_in and the next at u_out.
  auto edge = [&](double u_in, double f_in, double u_out, double f_out) {
    if (f_in <= f_out) return u_in;
    return u_in + (u_out - u_in) * std::clamp((f_in - vis) / (f_in - f_out), 0.0, 1.0);
  };
  SprayReport rep;
  rep.rect = rect_;
  rep.coat_width_nominal = tool_.coat_width;
  for (std::size_t s = 0; s < per_stroke_.size(); ++s) {
    const int si = static_cast<int>(s);
    CoatMeasure m;
    m.x = stroke_x[s];
    m.up = stroke_up[s];
    const int ixc = std::clamp(static_cast<int>(std::lround((m.x - x0_) / c)), 0, nx_ - 1);
    int lo = -1, hi = -1;
    for (int iy = 0; iy < ny_; ++iy) {
      if (stroke_film(si, ixc, iy) >= vis) {
        if (lo < 0) lo = iy;
        hi = iy;
      }
    }
    if (lo < 0) {
      m.bottom = m.top = std::nan("");
      rep.coats.push_back(m);
      continue;
    }
    m.bottom = lo > 0 ? edge(y0_ + lo * c, stroke_film(si, ixc, lo), y0_ + (lo - 1) * c, stroke_film(si, ixc, lo - 1)) : y0_;
    m.top = hi + 1 < ny_ ? edge(y0_ + hi * c, stroke_film(si, ixc, hi), y0_ + (hi + 1) * c, stroke_film(si, ixc, hi + 1))
                         : y0_ + hi * c;
    std::vector<double> widths;
    const int span = hi - lo;
    for (int iy = lo + span / 5; iy <= hi - span / 5; iy += 5) {
      if (stroke_film(si, ixc, iy) < vis) continue;
      int l = ixc, r = ixc;
      while (l > 0 && stroke_film(si, l - 1, iy) >= vis) --l;
      while (r + 1 < nx_ && stroke_film(si, r + 1, iy) >= vis) ++r;
      const double left = l > 0 ? edge(x0_ + l * c, stroke_film(si, l, iy), x0_ + (l - 1) * c, stroke_film(si, l - 1, iy)) : x0_;
      const double right =
          r + 1 < nx_ ? edge(x0_ + r * c, stroke_film(si, r, iy), x0_ + (r + 1) * c, stroke_film(si, r + 1, iy)) : x0_ + r * c;
      widths.push_back(right - left);
    }
    if (!widths.empty()) {
      std::sort(widths.begin(), widths.end());
      m.width = widths[widths.size() / 2];
      m.width_min = widths.front();
      m.width_max = widths.back();
      rep.max_width_error = std::max({rep.max_width_error, std::abs(m.width_min - tool_.coat_width),
                                      std::abs(m.width_max - tool_.coat_width)});
    }
    rep.coats.push_back(m);
  }
  for (std::size_t s = 0; s + 1 < rep.coats.size(); ++s) {
    rep.delta_bottom.push_back(rep.coats[s + 1].bottom - rep.coats[s].bottom);
    rep.delta_top.push_back(rep.coats[s + 1].top - rep.coats[s].top);
    rep.max_abs_delta_h = std::max(rep.max_abs_delta_h, std::abs(rep.delta_bottom.back()));
  }
  long inside = 0, painted = 0, outside_painted = 0;
  double sum = 0.0, sum2 = 0.0;
  for (int iy = 0; iy < ny_; ++iy) {
    const double y = y0_ + iy * c;
    for (int ix = 0; ix < nx_; ++ix) {
      const double x = x0_ + ix * c;
      const double f = film(ix, iy);
      const bool in = x >= rect_.x0 && x <= rect_.x1 && y >= rect_.y0 && y <= rect_.y1;
      if (in) {
        ++inside;
        sum += f;
        sum2 += f * f;
        if (f >= vis) ++painted;
      } else if (f >= vis) {
        ++outside_painted;
      }
    }
  }
  rep.coverage = inside > 0 ? static_cast<double>(painted) / static_cast<double>(inside) : 0.0;
  rep.overspray_area = static_cast<double>(outside_painted) * c * c;
  if (inside > 0) {
    rep.thickness_mean = sum / static_cast<double>(inside);
    const double var = std::max(0.0, sum2 / static_cast<double>(inside) - rep.thickness_mean * rep.thickness_mean);
    rep.thickness_cv = rep.thickness_mean > 0 ? std::sqrt(var) / rep.thickness_mean : 0.0;
  }
  return rep;
}

std::string SprayDeposition::to_json(const SprayReport& r) {
  auto mm = [](double m) { return std::isfinite(m) ? std::round(m * 10000.0) / 10.0 : -1.0; };
  nlohmann::json j;
  j["rect_mm"] = {mm(r.rect.x0), mm(r.rect.x1), mm(r.rect.y0), mm(r.rect.y1)};
  j["coat_width_nominal_mm"] = mm(r.coat_width_nominal);
  j["coats"] = nlohmann::json::array();
  for (std::size_t i = 0; i < r.coats.size(); ++i) {
    const CoatMeasure& c = r.coats[i];
    nlohmann::json cj = {{"stroke", i + 1},         {"x_mm", mm(c.x)},          {"direction", c.up ? "up" : "down"},
                         {"width_mm", mm(c.width)}, {"width_min_mm", mm(c.width_min)}, {"width_max_mm", mm(c.width_max)},
                         {"bottom_mm", mm(c.bottom)}, {"top_mm", mm(c.top)},   {"height_mm", mm(c.top - c.bottom)}};
    if (i > 0) {
      cj["delta_h_mm"] = mm(r.delta_bottom[i - 1]);
      cj["delta_top_mm"] = mm(r.delta_top[i - 1]);
    }
    j["coats"].push_back(cj);
  }
  j["coverage_percent"] = std::round(r.coverage * 10000.0) / 100.0;
  j["overspray_m2"] = std::round(r.overspray_area * 10000.0) / 10000.0;
  j["max_abs_delta_h_mm"] = mm(r.max_abs_delta_h);
  j["max_width_error_mm"] = mm(r.max_width_error);
  j["film_mean_coats"] = std::round(r.thickness_mean * 1000.0) / 1000.0;
  j["film_cv_percent"] = std::round(r.thickness_cv * 1000.0) / 10.0;
  return j.dump(2);
}

void SprayDeposition::write_png(const std::string& path) const {
  cv::Mat grey(ny_, nx_, CV_8UC1);
  for (int iy = 0; iy < ny_; ++iy) {
    for (int ix = 0; ix < nx_; ++ix) {
      grey.at<uint8_t>(ny_ - 1 - iy, ix) = static_cast<uint8_t>(std::clamp(film(ix, iy) / 2.0 * 255.0, 0.0, 255.0));
    }
  }
  cv::Mat img;
  cv::applyColorMap(grey, img, cv::COLORMAP_VIRIDIS);
  const double c = params_.cell;
  for (int iy = 0; iy < ny_; ++iy) {
    const double y = y0_ + iy * c;
    for (int ix = 0; ix < nx_; ++ix) {
      const double x = x0_ + ix * c;
      const bool in = x >= rect_.x0 && x <= rect_.x1 && y >= rect_.y0 && y <= rect_.y1;
      if (in && film(ix, iy) < params_.visible) img.at<cv::Vec3b>(ny_ - 1 - iy, ix) = cv::Vec3b(0, 0, 255);
    }
  }
  const auto px = [&](double x) { return static_cast<int>(std::lround((x - x0_) / c)); };
  const auto py = [&](double y) { return ny_ - 1 - static_cast<int>(std::lround((y - y0_) / c)); };
  cv::rectangle(img, cv::Point(px(rect_.x0), py(rect_.y1)), cv::Point(px(rect_.x1), py(rect_.y0)), cv::Scalar(255, 255, 255), 1);
  try {
    if (!cv::imwrite(path, img)) throw FinishError("cannot write the coverage map to " + path);
  } catch (const cv::Exception& e) {
    throw FinishError("cannot write the coverage map to " + path + ": " + e.what());
  }
}

}  // namespace concert::surface_finish
