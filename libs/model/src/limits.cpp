#include "concert/model/limits.hpp"

#include <cmath>
#include <set>

namespace concert::model {

bool position_violated(const JointLimits& j, double q, double tolerance) {
  return !std::isfinite(q) || q < j.lower - tolerance || q > j.upper + tolerance;
}

ThermalLoad::ThermalLoad(double window) : window_(window) {
  if (!(window > 0.0))
    throw ModelError("thermal window must be positive, got " + std::to_string(window) + " s");
}

double ThermalLoad::add(double tau, double dt) {
  const double square = tau * tau;
  if (!started_) {
    // The first sample only starts the clock: there is no period to weigh it by yet.
    started_ = true;
    return rms();
  }
  if (dt <= 0.0) return rms();
  const double alpha = 1.0 - std::exp(-dt / window_);
  mean_square_ += alpha * (square - mean_square_);
  return rms();
}

double folded_back_torque(const JointLimits& j, double rms) {
  const double start = kFoldbackStart * j.continuous_torque;
  if (!(rms > start)) return j.peak_torque;
  if (rms >= j.continuous_torque) return j.continuous_torque;
  const double s = (rms - start) / (j.continuous_torque - start);
  return j.peak_torque + s * (j.continuous_torque - j.peak_torque);
}

double ThermalLoad::rms() const { return std::sqrt(mean_square_); }

LimitsTable::LimitsTable(std::vector<JointLimits> rows, const std::string& where)
    : rows_(std::move(rows)), where_(where) {
  std::set<std::string> seen;
  for (const JointLimits& j : rows_) {
    const std::string at = where + ": joint '" + j.name + "': ";
    if (!seen.insert(j.name).second) throw ModelError(at + "listed twice in the limits table");
    if (std::isnan(j.lower) || std::isnan(j.upper) || j.lower > j.upper) {
      throw ModelError(at + "position limits [" + std::to_string(j.lower) + ", " +
                       std::to_string(j.upper) + "] are empty");
    }
    if (!(j.velocity > 0.0) || !std::isfinite(j.velocity)) {
      throw ModelError(at + "velocity limit " + std::to_string(j.velocity) +
                       " is not a positive number");
    }
    if (!(j.peak_torque > 0.0) || !std::isfinite(j.peak_torque)) {
      throw ModelError(at + "peak torque " + std::to_string(j.peak_torque) +
                       " is not a positive number");
    }
    if (!(j.continuous_torque > 0.0) || j.continuous_torque > j.peak_torque) {
      throw ModelError(at + "continuous torque " + std::to_string(j.continuous_torque) +
                       " is not in (0, peak torque " + std::to_string(j.peak_torque) + "]");
    }
  }
}

const JointLimits* LimitsTable::find(std::string_view joint) const {
  for (const JointLimits& j : rows_) {
    if (j.name == joint) return &j;
  }
  return nullptr;
}

const JointLimits& LimitsTable::at(std::string_view joint) const {
  if (const JointLimits* j = find(joint)) return *j;
  std::string known;
  for (const JointLimits& j : rows_) known += (known.empty() ? "" : ", ") + j.name;
  throw ModelError(where_ + ": no joint '" + std::string(joint) +
                   "' in the limits table (joints: " + (known.empty() ? "none" : known) + ")");
}

}  // namespace concert::model
