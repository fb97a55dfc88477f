#pragma once
// The drilling model of one simulator instance (see concert/sim/drilling.hpp). Control thread
// only; no allocation per step except when a hole opens.

#include <mujoco/mujoco.h>

#include <Eigen/Core>
#include <Eigen/Geometry>
#include <string>
#include <vector>

#include "concert/sim/drilling.hpp"
#include "concert/world/world.hpp"

namespace concert::sim {

class DrillingModel {
 public:
  DrillingModel() = default;
  /// Resolves the bits' links in `m` (throws HardwareError naming a link the model lacks) and
  /// takes the world's wall boxes.
  DrillingModel(const mjModel* m, const std::vector<DrillBit>& bits, const world::World& world,
                const DrillingParams& params);

  /// One physics step, before mj_step: sets the bits' bodies' xfrc_applied from the holes
  /// they are in (zero outside), opens holes, deepens them. `holes` persists across instances
  /// (holes stay in the wall when the robot is swapped). Returns true if a hole opened or got
  /// deeper by 0.1 mm or more since the last true.
  bool apply(const mjModel* m, mjData* d, std::vector<SimHole>& holes);

  [[nodiscard]] bool empty() const { return bits_.empty(); }

 private:
  struct Bit {
    DrillBit bit;
    int body{-1};
    int hole{-1};  ///< index in the holes the tip is in, or -1
  };
  struct Wall {
    std::string name;
    Eigen::Isometry3d pose{Eigen::Isometry3d::Identity()};  ///< world_T_box
    Eigen::Vector3d half{0, 0, 0};
  };
  /// The hole a tip at `p` (inside `wall`) enters: an existing one of the wall within a bit
  /// radius of the tip's axis, else a new one at the face it crossed.
  /// The robot's effective mass at the tip of `body` along `axis` [kg]: 1 / (a' J M^-1 J' a).
  double effective_mass(const mjModel* m, mjData* d, int body, const Eigen::Vector3d& p,
                        const Eigen::Vector3d& axis);
  int enter(const Bit& bit, const Wall& wall, const Eigen::Vector3d& p, const Eigen::Vector3d& axis,
            double time, std::vector<SimHole>& holes) const;

  std::vector<Bit> bits_;
  std::vector<Wall> walls_;
  DrillingParams params_;
  std::vector<double> reported_depth_;  ///< depth last reported per hole
  std::vector<mjtNum> jac_, u_, x_;     ///< effective-mass scratch (3 nv, nv, nv)
};

}  // namespace concert::sim
