#pragma once
// Simulated drilling: a drill bit that meets a wall cuts a hole instead of stopping at the
// surface, and the holes it cuts are recorded as ground truth for tests and benchmarks.
//
// MuJoCo has no material removal, so the bit has no collision shape (the URDF gives it none:
// the drill module's box ends 0.105 m behind the TCP) and this model acts on the tool instead,
// at the physics rate:
// * a bit tip that enters a wall box opens a hole at the face it crossed (or re-enters the
//   hole it is nearest to within a bit radius);
// * inside a hole the wall holds the bit on the hole's axis (a stiff lateral spring-damper at
//   the tip: a bit in a hole cannot move sideways) and resists feeding with the cutting force
//   of a hammer drill in concrete, thrust = threshold + feed damping x feed rate: the bit
//   advances only while the arm pushes harder than the threshold (paper §3: the platform
//   holds up to 200 N of drilling force);
// * the hole's depth is the deepest the tip went.

#include <Eigen/Core>
#include <string>
#include <vector>

namespace concert::sim {

/// A drill bit the robot carries: the TCP link of a drill end-effector, its z axis along the
/// bit (out of the tool), the tip at its origin.
struct DrillBit {
  std::string link;        ///< URDF link of the bit's tip (the drill end-effector's TCP frame)
  double diameter{0.012};  ///< [m] (the demo's add-on: a 12 mm SDS-max bit)
  bool operator==(const DrillBit&) const = default;
};

/// How a wall resists the bit (estimates for concrete and a hammer drill; no datasheet gives
/// them: hammer drills cut 12 mm holes in concrete at roughly 5-20 mm/s under 100-200 N).
struct DrillingParams {
  double thrust_threshold{20.0};    ///< [N] axial force below which the bit does not advance
  double feed_damping{6000.0};      ///< [N s/m] extra thrust per feed rate (10 mm/s: +60 N)
  double lateral_stiffness{2.0e4};  ///< [N/m] the hole holding the tip on its axis
  double lateral_damping{300.0};    ///< [N s/m]
};

/// A hole a bit cut (simulated truth).
struct SimHole {
  std::string wall;                      ///< the wall box it is in
  std::string bit;                       ///< the bit's link
  Eigen::Vector3d entry{0, 0, 0};        ///< where the hole's axis meets the face [m], world
  Eigen::Vector3d axis{0, 0, 0};         ///< unit, into the wall (the bit's axis at entry)
  Eigen::Vector3d face_normal{0, 0, 0};  ///< outward unit normal of the face it entered
  double depth{0.0};                     ///< deepest tip position along the axis [m]
  double diameter{0.0};                  ///< [m]
  double time{0.0};                      ///< simulated time it was started [s]
};

}  // namespace concert::sim
