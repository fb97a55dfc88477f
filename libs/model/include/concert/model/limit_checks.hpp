#pragma once
// The stop checks of the limits rule (limits.hpp) for a measured velocity and torque, beside
// model::position_violated: what safety applies to every joint sample. A measurement that is
// not finite (NaN, infinite) is a violation, as for the position.

#include <cmath>

#include "concert/model/limits.hpp"

namespace concert::model {

/// True when |qd| [rad/s] is beyond velocity_bound(j, margin), or qd is not finite.
inline bool velocity_violated(const JointLimits& j, double qd, double margin) {
  return !std::isfinite(qd) || std::abs(qd) > velocity_bound(j, margin);
}

/// True when |tau| [N m] is beyond instant_torque_bound(j, margin) (the peak torque with its
/// margin), or tau is not finite.
inline bool torque_violated(const JointLimits& j, double tau, double margin) {
  return !std::isfinite(tau) || std::abs(tau) > instant_torque_bound(j, margin);
}

}  // namespace concert::model
