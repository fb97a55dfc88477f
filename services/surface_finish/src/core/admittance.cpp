#include "surface_finish/admittance.hpp"

#include <opencv2/core.hpp>
#include <opencv2/imgcodecs.hpp>
#include <opencv2/imgproc.hpp>

#include <algorithm>
#include <cmath>
#include <cstdio>

namespace concert::surface_finish {

ForceAdmittance::ForceAdmittance(double setpoint, AdmittanceParams params) : target_(setpoint), params_(params) {
  if (!(params.kp > 0.0) || !(params.kd >= 0.0) || !(params.ramp_time >= 0.0) || !(params.max_speed > 0.0) ||
      !(params.max_offset > 0.0) || !(params.filter > 0.0)) {
    throw FinishError("admittance: kp, max_speed, max_offset, filter > 0 and kd, ramp_time >= 0 needed");
  }
  if (!(setpoint > 0.0) || !std::isfinite(setpoint)) throw FinishError("admittance: force setpoint must be positive");
}

double ForceAdmittance::setpoint() const {
  if (params_.ramp_time <= 0.0) return target_;
  return target_ * std::min(1.0, time_ / params_.ramp_time);
}

double ForceAdmittance::update(double force, double dt) {
  if (!(dt > 0.0) || !std::isfinite(force)) return offset_;
  time_ += dt;
  const double e = setpoint() - force;
  if (first_) {
    error_ = e;
    first_ = false;
  }
  const double raw = (e - error_) / dt;
  const double a = dt / (params_.filter + dt);
  rate_ += a * (raw - rate_);
  error_ = e;
  const double v = std::clamp(params_.kp * e + params_.kd * rate_, -params_.max_speed, params_.max_speed);
  offset_ = std::clamp(offset_ + v * dt, -params_.max_offset, params_.max_offset);
  return offset_;
}

ForceStats force_stats(const std::vector<ForceSample>& trace, double setpoint, double tolerance) {
  ForceStats s;
  double sum = 0.0, sum2 = 0.0, truth = 0.0, err2 = 0.0, within = 0.0;
  int n = 0, nt = 0;
  s.min = std::numeric_limits<double>::infinity();
  s.max = -s.min;
  for (std::size_t i = 0; i < trace.size(); ++i) {
    const ForceSample& f = trace[i];
    if (!f.stroke) continue;
    const double dt = i + 1 < trace.size() ? trace[i + 1].t - f.t : (i > 0 ? f.t - trace[i - 1].t : 0.0);
    s.duration += dt;
    ++n;
    sum += f.estimated;
    sum2 += f.estimated * f.estimated;
    s.min = std::min(s.min, f.estimated);
    s.max = std::max(s.max, f.estimated);
    if (std::abs(f.estimated - setpoint) <= tolerance) {
      within += dt;
    } else {
      s.time_outside += dt;
    }
    if (std::isfinite(f.truth)) {
      ++nt;
      truth += f.truth;
      err2 += (f.estimated - f.truth) * (f.estimated - f.truth);
    }
  }
  if (n == 0) throw FinishError("force statistics: the trace has no stroke sample");
  s.mean = sum / n;
  s.std_dev = std::sqrt(std::max(0.0, sum2 / n - s.mean * s.mean));
  s.within_fraction = s.duration > 0.0 ? within / s.duration : 0.0;
  s.truth_mean = nt > 0 ? truth / nt : std::nan("");
  s.estimate_error_rms = nt > 0 ? std::sqrt(err2 / nt) : std::nan("");
  return s;
}

void write_force_png(const std::vector<ForceSample>& trace, double setpoint, double tolerance, const std::string& path) {
  if (trace.empty()) throw FinishError("force plot: empty trace");
  const int w = 900, h = 420, left = 60, right = 20, top = 20, bottom = 40;
  cv::Mat img(h, w, CV_8UC3, cv::Scalar(255, 255, 255));
  const double t0 = trace.front().t, t1 = std::max(trace.back().t, t0 + 1e-3);
  double fmax = setpoint + 3.0 * tolerance;
  for (const ForceSample& f : trace) fmax = std::max({fmax, f.estimated, std::isfinite(f.truth) ? f.truth : 0.0});
  const auto px = [&](double t) { return left + static_cast<int>((t - t0) / (t1 - t0) * (w - left - right)); };
  const auto py = [&](double f) { return h - bottom - static_cast<int>(std::clamp(f / fmax, -0.05, 1.0) * (h - top - bottom)); };
  cv::rectangle(img, cv::Point(left, py(setpoint + tolerance)), cv::Point(w - right, py(setpoint - tolerance)),
                cv::Scalar(220, 240, 220), cv::FILLED);
  cv::line(img, cv::Point(left, py(setpoint)), cv::Point(w - right, py(setpoint)), cv::Scalar(0, 150, 0), 1);
  cv::line(img, cv::Point(left, py(0)), cv::Point(w - right, py(0)), cv::Scalar(0, 0, 0), 1);
  cv::line(img, cv::Point(left, top), cv::Point(left, h - bottom), cv::Scalar(0, 0, 0), 1);
  for (std::size_t i = 1; i < trace.size(); ++i) {
    const ForceSample& a = trace[i - 1];
    const ForceSample& b = trace[i];
    if (std::isfinite(a.truth) && std::isfinite(b.truth)) {
      cv::line(img, cv::Point(px(a.t), py(a.truth)), cv::Point(px(b.t), py(b.truth)), cv::Scalar(180, 120, 0), 1);
    }
    cv::line(img, cv::Point(px(a.t), py(a.estimated)), cv::Point(px(b.t), py(b.estimated)), cv::Scalar(0, 0, 200), 1);
  }
  char b[160];
  std::snprintf(b, sizeof b, "force [N] 0..%.0f over %.1f s: red estimate (joint torques), blue truth, green %.0f +- %.0f N",
                fmax, t1 - t0, setpoint, tolerance);
  cv::putText(img, b, cv::Point(left, h - 12), cv::FONT_HERSHEY_SIMPLEX, 0.45, cv::Scalar(0, 0, 0), 1);
  try {
    if (!cv::imwrite(path, img)) throw FinishError("cannot write the force plot to " + path);
  } catch (const cv::Exception& e) {
    throw FinishError("cannot write the force plot to " + path + ": " + e.what());
  }
}

}  // namespace concert::surface_finish
