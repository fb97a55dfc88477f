#include "nav/localiser.hpp"

#include <Eigen/Dense>
#include <algorithm>
#include <cmath>
#include <limits>
#include <numbers>
#include <string>
#include <unordered_map>

#include "concert/mobile_base/map_frame.hpp"

namespace concert::nav {

namespace {

using bim::OccupancyGrid;

double wrap(double angle) {
  angle = std::remainder(angle, 2.0 * std::numbers::pi);
  return angle <= -std::numbers::pi ? angle + 2.0 * std::numbers::pi : angle;
}

bool occupied_cell(std::int8_t value) { return value >= 50; }

// a * b and a^-1 for planar poses (x, y, yaw).
using mobile_base::compose;
using mobile_base::inverse;

// 1D squared Euclidean distance transform of f (Felzenszwalb & Huttenlocher 2012): d[q] =
// min_p (q - p)^2 + f[p]. v, z: scratch of n and n + 1 entries.
void distance_transform_1d(const std::vector<double>& f, std::vector<double>& d,
                           std::vector<int>& v, std::vector<double>& z) {
  const int n = static_cast<int>(f.size());
  const double inf = std::numeric_limits<double>::infinity();
  auto intersection = [&](int q, int p) {
    return ((f[static_cast<std::size_t>(q)] + double(q) * q) -
            (f[static_cast<std::size_t>(p)] + double(p) * p)) /
           (2.0 * q - 2.0 * p);
  };
  std::size_t k = 0;
  v[0] = 0;
  z[0] = -inf;
  z[1] = inf;
  for (int q = 1; q < n; ++q) {
    double s = intersection(q, v[k]);
    while (s <= z[k]) {
      --k;
      s = intersection(q, v[k]);
    }
    ++k;
    v[k] = q;
    z[k] = s;
    z[k + 1] = inf;
  }
  k = 0;
  for (int q = 0; q < n; ++q) {
    while (z[k + 1] < q) ++k;
    const int p = v[k];
    d[static_cast<std::size_t>(q)] = double(q - p) * (q - p) + f[static_cast<std::size_t>(p)];
  }
}

}  // namespace

double cast_ray(const OccupancyGrid& grid, const Eigen::Vector2d& origin, double angle,
                double max_range) {
  const double res = grid.resolution;
  const Eigen::Vector2d g = (origin - grid.origin) / res;
  int col = static_cast<int>(std::floor(g.x()));
  int row = static_cast<int>(std::floor(g.y()));
  if (!grid.inside(col, row) || occupied_cell(grid.at(col, row))) return 0.0;
  const Eigen::Vector2d dir(std::cos(angle), std::sin(angle));
  const double inf = std::numeric_limits<double>::infinity();
  const int step_x = dir.x() > 0.0 ? 1 : -1;
  const int step_y = dir.y() > 0.0 ? 1 : -1;
  double t_max_x = dir.x() != 0.0 ? ((col + (step_x > 0 ? 1 : 0)) - g.x()) / dir.x() * res : inf;
  double t_max_y = dir.y() != 0.0 ? ((row + (step_y > 0 ? 1 : 0)) - g.y()) / dir.y() * res : inf;
  const double t_delta_x = dir.x() != 0.0 ? res / std::abs(dir.x()) : inf;
  const double t_delta_y = dir.y() != 0.0 ? res / std::abs(dir.y()) : inf;
  while (true) {
    double t = 0.0;
    if (t_max_x < t_max_y) {
      t = t_max_x;
      col += step_x;
      t_max_x += t_delta_x;
    } else {
      t = t_max_y;
      row += step_y;
      t_max_y += t_delta_y;
    }
    if (t >= max_range) return max_range;
    if (!grid.inside(col, row) || occupied_cell(grid.at(col, row))) return t;
  }
}

LikelihoodField::LikelihoodField(OccupancyGrid grid, double max_distance)
    : grid_(std::move(grid)), max_distance_(max_distance) {
  if (grid_.width <= 0 || grid_.height <= 0 || !(grid_.resolution > 0.0) ||
      grid_.cells.size() != static_cast<std::size_t>(grid_.width) * grid_.height) {
    throw LocaliserError("likelihood field: the grid is empty or its cell count (" +
                         std::to_string(grid_.cells.size()) + ") is not width x height (" +
                         std::to_string(grid_.width) + " x " + std::to_string(grid_.height) + ")");
  }
  if (!(max_distance > 0.0) || !std::isfinite(max_distance)) {
    throw LocaliserError("likelihood field: max_distance must be positive, got " +
                         std::to_string(max_distance));
  }
  if (std::none_of(grid_.cells.begin(), grid_.cells.end(), occupied_cell)) {
    throw LocaliserError("likelihood field: the map has no occupied cell: nothing to localise on");
  }
  const int w = grid_.width, h = grid_.height;
  const double far = 1e20;
  std::vector<double> squared(grid_.cells.size());
  for (std::size_t i = 0; i < squared.size(); ++i)
    squared[i] = occupied_cell(grid_.cells[i]) ? 0.0 : far;
  const int n = std::max(w, h);
  std::vector<double> f(static_cast<std::size_t>(n)), d(static_cast<std::size_t>(n));
  std::vector<int> v(static_cast<std::size_t>(n));
  std::vector<double> z(static_cast<std::size_t>(n) + 1);
  // Separable: along every column, then along every row of the column pass's result.
  auto transform_lines = [&](int lines, int length, auto index) {
    f.resize(static_cast<std::size_t>(length));
    d.resize(static_cast<std::size_t>(length));
    for (int a = 0; a < lines; ++a) {
      for (int b = 0; b < length; ++b) f[static_cast<std::size_t>(b)] = squared[index(a, b)];
      distance_transform_1d(f, d, v, z);
      for (int b = 0; b < length; ++b) squared[index(a, b)] = d[static_cast<std::size_t>(b)];
    }
  };
  transform_lines(w, h, [&](int col, int row) { return grid_.index(col, row); });
  transform_lines(h, w, [&](int row, int col) { return grid_.index(col, row); });
  centre_distance_.resize(squared.size());
  for (std::size_t i = 0; i < squared.size(); ++i) {
    centre_distance_[i] = static_cast<float>(
        std::min(std::sqrt(squared[i]) * grid_.resolution, max_distance_ + grid_.resolution));
  }
}

double LikelihoodField::distance(const Eigen::Vector2d& p) const {
  Eigen::Vector2d unused;
  return distance(p, unused);
}

double LikelihoodField::distance(const Eigen::Vector2d& p, Eigen::Vector2d& gradient) const {
  gradient.setZero();
  const double res = grid_.resolution;
  const double u = (p.x() - grid_.origin.x()) / res - 0.5;
  const double v = (p.y() - grid_.origin.y()) / res - 0.5;
  if (!(u >= 0.0 && v >= 0.0 && u < grid_.width - 1 && v < grid_.height - 1)) return max_distance_;
  const int i = static_cast<int>(u), j = static_cast<int>(v);
  const double fx = u - i, fy = v - j;
  const std::size_t i00 = grid_.index(i, j);
  const std::size_t i01 = i00 + static_cast<std::size_t>(grid_.width);
  const double d00 = centre_distance_[i00], d10 = centre_distance_[i00 + 1];
  const double d01 = centre_distance_[i01], d11 = centre_distance_[i01 + 1];
  const double b =
      (1 - fx) * (1 - fy) * d00 + fx * (1 - fy) * d10 + (1 - fx) * fy * d01 + fx * fy * d11;
  const double d = b - 0.5 * res;
  if (d <= 0.0) return 0.0;
  if (d >= max_distance_) return max_distance_;
  gradient.x() = ((1 - fy) * (d10 - d00) + fy * (d11 - d01)) / res;
  gradient.y() = ((1 - fx) * (d01 - d00) + fx * (d11 - d10)) / res;
  return d;
}

std::vector<Eigen::Vector2d> LikelihoodField::free_cells(double clearance) const {
  std::vector<Eigen::Vector2d> out;
  for (int row = 0; row < grid_.height; ++row) {
    for (int col = 0; col < grid_.width; ++col) {
      const std::size_t i = grid_.index(col, row);
      if (grid_.cells[i] == OccupancyGrid::kFree && centre_distance_[i] >= clearance) {
        out.push_back(grid_.center_of(col, row));
      }
    }
  }
  return out;
}

Localiser::Localiser(std::shared_ptr<const LikelihoodField> field, const LocaliserParams& params)
    : field_(std::move(field)), params_(params), rng_(params.seed) {
  if (!field_) throw LocaliserError("localiser: no likelihood field (map)");
  auto require = [](bool ok, const char* name, double value) {
    if (!ok) {
      throw LocaliserError(std::string("localiser parameter ") + name +
                           " out of range: " + std::to_string(value));
    }
  };
  require(params.particles >= 10, "particles (>= 10)", params.particles);
  require(params.recovery_particles >= params.particles, "recovery_particles (>= particles)",
          params.recovery_particles);
  require(params.max_beams >= 1, "max_beams (>= 1)", params.max_beams);
  require(params.refine_beams >= 1, "refine_beams (>= 1)", params.refine_beams);
  require(params.sigma_hit > 0.0, "sigma_hit (> 0)", params.sigma_hit);
  require(params.z_hit > 0.0 && params.z_rand > 0.0, "z_hit, z_rand (> 0)", params.z_rand);
  require(params.beam_exponent > 0.0 && params.beam_exponent <= 1.0, "beam_exponent (0, 1]",
          params.beam_exponent);
  require(params.resample_ratio > 0.0 && params.resample_ratio <= 1.0, "resample_ratio (0, 1]",
          params.resample_ratio);
  require(params.lost_after >= 1, "lost_after (>= 1)", params.lost_after);
  require(params.converged_after >= 1, "converged_after (>= 1)", params.converged_after);
  // Log-likelihood of a beam ending d from the map: z_hit * exp(-d^2 / 2 sigma^2) + z_rand / d_max,
  // tabulated per millimetre up to the field's max distance.
  const double two_sigma2 = 2.0 * params.sigma_hit * params.sigma_hit;
  const double floor = params.z_rand / field_->max_distance();
  const auto steps = static_cast<std::size_t>(std::ceil(field_->max_distance() * 1000.0)) + 1;
  beam_log_likelihood_.resize(steps);
  for (std::size_t k = 0; k < steps; ++k) {
    const double d = static_cast<double>(k) * 1e-3;
    beam_log_likelihood_[k] = std::log(params.z_hit * std::exp(-d * d / two_sigma2) + floor);
  }
}

void Localiser::set_pose(const Eigen::Vector3d& map_pose, const Eigen::Vector3d& sigma,
                         const Eigen::Vector3d& odom_pose) {
  if (!map_pose.allFinite() || !sigma.allFinite() || !odom_pose.allFinite() ||
      (sigma.array() < 0.0).any()) {
    throw LocaliserError(
        "localiser: initial pose, its spread or the odometry pose is not finite "
        "(or a spread is negative)");
  }
  std::normal_distribution<double> n01(0.0, 1.0);
  particles_.resize(static_cast<std::size_t>(params_.particles));
  const double w = 1.0 / params_.particles;
  for (Particle& p : particles_) {
    p.pose = map_pose +
             Eigen::Vector3d(sigma.x() * n01(rng_), sigma.y() * n01(rng_), sigma.z() * n01(rng_));
    p.pose.z() = wrap(p.pose.z());
    p.weight = w;
  }
  have_odom_ = true;
  last_odom_ = odom_pose;
  weigh_next_ = true;
  estimate_ = LocaliserEstimate{};
  estimate_.status = LocaliserStatus::kTracking;
  estimate_.pose = map_pose;
  estimate_.map_T_odom = compose(map_pose, inverse(odom_pose));
  estimate_.covariance = sigma.cwiseAbs2().asDiagonal();
  estimate_.effective_particles = params_.particles;
}

void Localiser::spread(const Eigen::Vector3d& odom_pose) {
  if (!odom_pose.allFinite()) throw LocaliserError("localiser: odometry pose is not finite");
  const std::vector<Eigen::Vector2d> free = field_->free_cells(params_.recovery_clearance);
  if (free.empty()) {
    throw LocaliserError("localiser: the map has no free cell with " +
                         std::to_string(params_.recovery_clearance) +
                         " m clearance to spread over");
  }
  std::uniform_int_distribution<std::size_t> pick(0, free.size() - 1);
  std::uniform_real_distribution<double> jitter(-0.5, 0.5);
  std::uniform_real_distribution<double> yaw(-std::numbers::pi, std::numbers::pi);
  const double res = field_->grid().resolution;
  particles_.resize(static_cast<std::size_t>(params_.recovery_particles));
  const double w = 1.0 / params_.recovery_particles;
  for (Particle& p : particles_) {
    const Eigen::Vector2d& c = free[pick(rng_)];
    p.pose = Eigen::Vector3d(c.x() + res * jitter(rng_), c.y() + res * jitter(rng_), yaw(rng_));
    p.weight = w;
  }
  have_odom_ = true;
  last_odom_ = odom_pose;
  weigh_next_ = true;
  estimate_.status = LocaliserStatus::kLost;
  estimate_.low_match_updates = 0;
  converging_updates_ = 0;
  estimate_.refined = false;
}

void Localiser::collect_beams(int count, std::vector<Beam>& out) const {
  out.clear();
  const std::size_t valid = all_beams_.size();
  if (valid == 0) return;
  const std::size_t n = std::min(valid, static_cast<std::size_t>(count));
  for (std::size_t i = 0; i < n; ++i) out.push_back(all_beams_[i * valid / n]);
}

void Localiser::move_particles(const Eigen::Vector3d& delta) {
  const double trans = delta.head<2>().norm();
  const double rot = std::abs(delta.z());
  if (trans < 1e-9 && rot < 1e-9) return;
  const double sigma_t = params_.alpha_trans_trans * trans + params_.alpha_trans_rot * rot;
  const double sigma_r = params_.alpha_rot_rot * rot + params_.alpha_rot_trans * trans;
  std::normal_distribution<double> n01(0.0, 1.0);
  for (Particle& p : particles_) {
    const Eigen::Vector3d noisy(delta.x() + sigma_t * n01(rng_), delta.y() + sigma_t * n01(rng_),
                                delta.z() + sigma_r * n01(rng_));
    p.pose = compose(p.pose, noisy);
  }
}

void Localiser::weigh_particles() {
  const std::size_t last = beam_log_likelihood_.size() - 1;
  log_likelihood_.resize(particles_.size());
  double best = -std::numeric_limits<double>::infinity();
  for (std::size_t k = 0; k < particles_.size(); ++k) {
    const Eigen::Vector3d& pose = particles_[k].pose;
    const double c = std::cos(pose.z()), s = std::sin(pose.z());
    double sum = 0.0;
    for (const Beam& b : weigh_beams_) {
      const Eigen::Vector2d p(pose.x() + c * b.x - s * b.y, pose.y() + s * b.x + c * b.y);
      const auto mm = static_cast<std::size_t>(field_->distance(p) * 1000.0 + 0.5);
      sum += beam_log_likelihood_[std::min(mm, last)];
    }
    const double lw =
        std::log(std::max(particles_[k].weight, 1e-300)) + params_.beam_exponent * sum;
    log_likelihood_[k] = lw;
    best = std::max(best, lw);
  }
  double total = 0.0;
  for (std::size_t k = 0; k < particles_.size(); ++k) {
    particles_[k].weight = std::exp(log_likelihood_[k] - best);
    total += particles_[k].weight;
  }
  double sum_sq = 0.0;
  for (Particle& p : particles_) {
    p.weight /= total;
    sum_sq += p.weight * p.weight;
  }
  estimate_.effective_particles = 1.0 / sum_sq;
}

void Localiser::resample(int count) {
  // Low-variance (systematic) resampling.
  std::uniform_real_distribution<double> start(0.0, 1.0 / count);
  scratch_.clear();
  double r = start(rng_);
  double cumulative = particles_[0].weight;
  std::size_t i = 0;
  const double w = 1.0 / count;
  for (int m = 0; m < count; ++m) {
    const double u = r + static_cast<double>(m) * w;
    while (u > cumulative && i + 1 < particles_.size()) cumulative += particles_[++i].weight;
    scratch_.push_back({particles_[i].pose, w});
  }
  particles_.swap(scratch_);
}

void Localiser::estimate_pose(const Eigen::Vector3d& odom_pose) {
  // Mode: the heaviest cell of a coarse (x, y, yaw) histogram, then the particles near it.
  struct Bin {
    double weight{0.0}, x{0.0}, y{0.0}, c{0.0}, s{0.0};
  };
  std::unordered_map<std::int64_t, Bin> bins;
  const double r = params_.cluster_radius, a = params_.cluster_angle;
  for (const Particle& p : particles_) {
    const auto ix = static_cast<std::int64_t>(std::floor(p.pose.x() / r));
    const auto iy = static_cast<std::int64_t>(std::floor(p.pose.y() / r));
    const auto ia = static_cast<std::int64_t>(std::floor((p.pose.z() + std::numbers::pi) / a));
    Bin& b = bins[(ix * 100003 + iy) * 64 + ia];
    b.weight += p.weight;
    b.x += p.weight * p.pose.x();
    b.y += p.weight * p.pose.y();
    b.c += p.weight * std::cos(p.pose.z());
    b.s += p.weight * std::sin(p.pose.z());
  }
  const Bin* top = nullptr;
  for (const auto& [key, b] : bins) {
    if (top == nullptr || b.weight > top->weight) top = &b;
  }
  const Eigen::Vector3d seed(top->x / top->weight, top->y / top->weight,
                             std::atan2(top->s, top->c));
  double w = 0.0, x = 0.0, y = 0.0, c = 0.0, s = 0.0;
  for (const Particle& p : particles_) {
    if ((p.pose.head<2>() - seed.head<2>()).norm() > r || std::abs(wrap(p.pose.z() - seed.z())) > a)
      continue;
    w += p.weight;
    x += p.weight * p.pose.x();
    y += p.weight * p.pose.y();
    c += p.weight * std::cos(p.pose.z());
    s += p.weight * std::sin(p.pose.z());
  }
  if (!(w > 0.0)) {  // the heaviest bin's particles all lie beyond its mean's radius
    w = top->weight;
    x = top->x;
    y = top->y;
    c = top->c;
    s = top->s;
  }
  const Eigen::Vector3d mean(x / w, y / w, std::atan2(s, c));
  Eigen::Matrix3d cov = Eigen::Matrix3d::Zero();
  for (const Particle& p : particles_) {
    if ((p.pose.head<2>() - seed.head<2>()).norm() > r || std::abs(wrap(p.pose.z() - seed.z())) > a)
      continue;
    const Eigen::Vector3d e(p.pose.x() - mean.x(), p.pose.y() - mean.y(),
                            wrap(p.pose.z() - mean.z()));
    cov += (p.weight / w) * e * e.transpose();
  }
  Eigen::Vector3d pose = mean;
  estimate_.refined = params_.refine && refine(pose);
  estimate_.pose = pose;
  estimate_.covariance = cov;
  estimate_.map_T_odom = compose(pose, inverse(odom_pose));
  estimate_.match_ratio = match_ratio(pose);
}

bool Localiser::refine(Eigen::Vector3d& pose) const {
  const double outlier = params_.refine_outlier;
  auto cost = [&](const Eigen::Vector3d& q) {
    const double c = std::cos(q.z()), s = std::sin(q.z());
    double sum = 0.0;
    for (const Beam& b : refine_beams_) {
      const double d = field_->distance({q.x() + c * b.x - s * b.y, q.y() + s * b.x + c * b.y});
      sum += std::min(d, outlier) * std::min(d, outlier);
    }
    return sum;
  };
  Eigen::Vector3d q = pose;
  for (int iteration = 0; iteration < params_.refine_iterations; ++iteration) {
    const double c = std::cos(q.z()), s = std::sin(q.z());
    Eigen::Matrix3d h = Eigen::Matrix3d::Zero();
    Eigen::Vector3d g = Eigen::Vector3d::Zero();
    int used = 0;
    for (const Beam& b : refine_beams_) {
      const Eigen::Vector2d p(q.x() + c * b.x - s * b.y, q.y() + s * b.x + c * b.y);
      Eigen::Vector2d grad;
      const double d = field_->distance(p, grad);
      if (d >= outlier || d <= 0.0) continue;
      const Eigen::Vector3d j(grad.x(), grad.y(),
                              grad.x() * (-s * b.x - c * b.y) + grad.y() * (c * b.x - s * b.y));
      h += j * j.transpose();
      g += j * d;
      ++used;
    }
    if (used < 10) break;
    const Eigen::Vector3d step = -(h + 1e-6 * Eigen::Matrix3d::Identity()).ldlt().solve(g);
    if (!step.allFinite()) return false;
    q += step;
    q.z() = wrap(q.z());
    if (step.head<2>().norm() < 1e-4 && std::abs(step.z()) < 1e-4) break;
  }
  if ((q.head<2>() - pose.head<2>()).norm() > params_.refine_max_shift ||
      std::abs(wrap(q.z() - pose.z())) > params_.refine_max_turn || cost(q) >= cost(pose)) {
    return false;
  }
  pose = q;
  return true;
}

double Localiser::match_ratio(const Eigen::Vector3d& pose) const {
  if (all_beams_.empty()) return 0.0;
  const double c = std::cos(pose.z()), s = std::sin(pose.z());
  int matched = 0;
  for (const Beam& b : all_beams_) {
    const Eigen::Vector2d p(pose.x() + c * b.x - s * b.y, pose.y() + s * b.x + c * b.y);
    if (field_->distance(p) <= params_.match_distance) ++matched;
  }
  return static_cast<double>(matched) / static_cast<double>(all_beams_.size());
}

const LocaliserEstimate& Localiser::update(const Eigen::Vector3d& odom_pose,
                                           const PlanarScan& scan) {
  if (!odom_pose.allFinite()) throw LocaliserError("localiser: odometry pose is not finite");
  if (scan.angles.size() != scan.ranges.size()) {
    throw LocaliserError("localiser: scan has " + std::to_string(scan.angles.size()) +
                         " angles but " + std::to_string(scan.ranges.size()) + " ranges");
  }
  if (!std::isfinite(scan.range_min) || !std::isfinite(scan.range_max) ||
      scan.range_max <= scan.range_min) {
    throw LocaliserError("localiser: scan range limits [" + std::to_string(scan.range_min) + ", " +
                         std::to_string(scan.range_max) + "] are not a finite interval");
  }
  for (std::size_t i = 0; i < scan.angles.size(); ++i) {
    if (!std::isfinite(scan.angles[i])) {
      throw LocaliserError("localiser: scan angle " + std::to_string(i) + " is not finite");
    }
  }
  if (!have_odom_) spread(odom_pose);

  all_beams_.clear();
  for (std::size_t i = 0; i < scan.ranges.size(); ++i) {
    const double r = scan.ranges[i];
    if (!std::isfinite(r) || r < scan.range_min || r > scan.range_max || r <= 0.0) continue;
    all_beams_.push_back({r * std::cos(scan.angles[i]), r * std::sin(scan.angles[i])});
  }
  collect_beams(params_.max_beams, weigh_beams_);
  collect_beams(params_.refine_beams, refine_beams_);

  const Eigen::Vector3d delta = compose(inverse(last_odom_), odom_pose);
  last_odom_ = odom_pose;
  move_particles(delta);
  motion_since_weighing_ += delta.cwiseAbs();
  if (all_beams_.empty()) {  // nothing seen: dead reckoning on the last correction
    estimate_.pose = compose(estimate_.map_T_odom, odom_pose);
    estimate_.refined = false;
    estimate_.match_ratio = 0.0;
    return estimate_;
  }
  const bool weighed = weigh_next_ ||
                       motion_since_weighing_.head<2>().norm() >= params_.update_min_distance ||
                       motion_since_weighing_.z() >= params_.update_min_angle;
  if (weighed) {
    weigh_particles();
    motion_since_weighing_.setZero();
    weigh_next_ = false;
    if (static_cast<int>(particles_.size()) != params_.particles ||
        estimate_.effective_particles < params_.resample_ratio * params_.particles) {
      resample(params_.particles);
    }
  }
  estimate_pose(odom_pose);

  const bool low = estimate_.match_ratio < params_.lost_match_ratio;
  estimate_.low_match_updates = low ? estimate_.low_match_updates + 1 : 0;
  if (estimate_.status == LocaliserStatus::kLost && weighed) {
    const bool good = estimate_.refined && estimate_.match_ratio >= params_.converged_match_ratio &&
                      std::sqrt(estimate_.covariance(0, 0) + estimate_.covariance(1, 1)) <
                          params_.converged_sigma_xy &&
                      std::sqrt(estimate_.covariance(2, 2)) < params_.converged_sigma_yaw;
    converging_updates_ = good ? converging_updates_ + 1 : 0;
    if (converging_updates_ >= params_.converged_after)
      estimate_.status = LocaliserStatus::kTracking;
  }
  if (estimate_.low_match_updates >= params_.lost_after) spread(odom_pose);
  return estimate_;
}

}  // namespace concert::nav
