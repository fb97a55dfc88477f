#include "drilling_model.hpp"

#include <algorithm>
#include <cmath>

#include "concert/hardware/hardware.hpp"

namespace concert::sim {
namespace {

// A hole's depth is reported again once it grew by this [m].
constexpr double kReportStep = 1e-4;

Eigen::Isometry3d body_pose(const mjData* d, int body) {
  Eigen::Isometry3d pose = Eigen::Isometry3d::Identity();
  for (int r = 0; r < 3; ++r) {
    pose.translation()(r) = d->xpos[3 * body + r];
    for (int c = 0; c < 3; ++c) pose.linear()(r, c) = d->xmat[9 * body + 3 * r + c];
  }
  return pose;
}

}  // namespace

DrillingModel::DrillingModel(const mjModel* m, const std::vector<DrillBit>& bits,
                             const world::World& world, const DrillingParams& params)
    : params_(params) {
  for (const DrillBit& b : bits) {
    const int body = mj_name2id(m, mjOBJ_BODY, b.link.c_str());
    if (body < 0) {
      throw hardware::HardwareError("sim: drill bit link '" + b.link +
                                    "' is not a link of the robot");
    }
    if (!(b.diameter > 0.0)) {
      throw hardware::HardwareError("sim: drill bit '" + b.link + "' needs a positive diameter");
    }
    bits_.push_back({b, body, -1});
  }
  jac_.resize(static_cast<std::size_t>(3 * m->nv));
  u_.resize(static_cast<std::size_t>(m->nv));
  x_.resize(static_cast<std::size_t>(m->nv));
  for (const world::WorldShape& w : world.walls) {
    if (w.type != world::WorldShape::Type::kBox) continue;
    Wall wall;
    wall.name = w.name;
    wall.pose.translation() = w.position;
    wall.pose.linear() = Eigen::AngleAxisd(w.yaw, Eigen::Vector3d::UnitZ()).toRotationMatrix();
    wall.half = 0.5 * w.size;
    walls_.push_back(wall);
  }
}

int DrillingModel::enter(const Bit& bit, const Wall& wall, const Eigen::Vector3d& p,
                         const Eigen::Vector3d& axis, double time,
                         std::vector<SimHole>& holes) const {
  const double radius = 0.5 * bit.bit.diameter;
  for (std::size_t i = 0; i < holes.size(); ++i) {
    const SimHole& h = holes[i];
    if (h.wall != wall.name) continue;
    const Eigen::Vector3d r = p - h.entry;
    if ((r - r.dot(h.axis) * h.axis).norm() < radius) return static_cast<int>(i);
  }
  // The face the tip crossed: of the box's four vertical faces, the one it is least deep
  // behind (the top of a wall is not drilled from above here).
  const Eigen::Vector3d local = wall.pose.inverse() * p;
  int best_axis = 0;
  double best_depth = wall.half.x() - std::abs(local.x());
  if (wall.half.y() - std::abs(local.y()) < best_depth) {
    best_axis = 1;
    best_depth = wall.half.y() - std::abs(local.y());
  }
  Eigen::Vector3d n_local = Eigen::Vector3d::Zero();
  n_local(best_axis) = local(best_axis) >= 0.0 ? 1.0 : -1.0;
  const Eigen::Vector3d n = wall.pose.linear() * n_local;
  // Where the bit's axis through the tip meets the face plane.
  const Eigen::Vector3d face_point = wall.pose * (n_local * wall.half(best_axis));
  const double along = axis.dot(n);
  const Eigen::Vector3d entry = std::abs(along) > 1e-6
                                    ? Eigen::Vector3d(p + axis * ((face_point - p).dot(n) / along))
                                    : Eigen::Vector3d(p + n * best_depth);
  SimHole h;
  h.wall = wall.name;
  h.bit = bit.bit.link;
  h.entry = entry;
  h.axis = axis;
  h.face_normal = n;
  h.depth = (p - entry).dot(axis);
  h.diameter = bit.bit.diameter;
  h.time = time;
  holes.push_back(h);
  return static_cast<int>(holes.size()) - 1;
}

double DrillingModel::effective_mass(const mjModel* m, mjData* d, int body,
                                     const Eigen::Vector3d& p, const Eigen::Vector3d& axis) {
  mj_jac(m, d, jac_.data(), nullptr, p.data(), body);
  for (int i = 0; i < m->nv; ++i) {
    u_[i] = axis.x() * jac_[i] + axis.y() * jac_[m->nv + i] + axis.z() * jac_[2 * m->nv + i];
  }
  mj_solveM(m, d, x_.data(), u_.data(), 1);
  const double inverse = mju_dot(u_.data(), x_.data(), m->nv);
  return inverse > 1e-12 ? 1.0 / inverse : 1e12;
}

bool DrillingModel::apply(const mjModel* m, mjData* d, std::vector<SimHole>& holes) {
  bool changed = false;
  for (Bit& bit : bits_) {
    mjtNum* f = d->xfrc_applied + 6 * bit.body;
    std::fill_n(f, 6, 0.0);
    const Eigen::Isometry3d tip = body_pose(d, bit.body);
    const Eigen::Vector3d p = tip.translation();
    const Eigen::Vector3d axis = tip.linear().col(2);
    if (bit.hole < 0) {
      for (const Wall& wall : walls_) {
        const Eigen::Vector3d local = wall.pose.inverse() * p;
        if ((local.cwiseAbs() - wall.half).maxCoeff() < 0.0) {
          bit.hole = enter(bit, wall, p, axis, d->time, holes);
          changed = true;
          break;
        }
      }
      if (bit.hole < 0) continue;
    }
    SimHole& hole = holes[static_cast<std::size_t>(bit.hole)];
    const double depth = (p - hole.entry).dot(hole.axis);
    if (depth <= 0.0) {  // pulled out
      bit.hole = -1;
      continue;
    }
    if (depth > hole.depth) hole.depth = depth;
    // The tip's velocity (MuJoCo gives [angular; linear] at the body's origin, world-aligned).
    mjtNum vel[6];
    mj_objectVelocity(m, d, mjOBJ_BODY, bit.body, vel, 0);
    const Eigen::Vector3d v(vel[3], vel[4], vel[5]);
    const Eigen::Vector3d offset = (p - hole.entry) - depth * hole.axis;
    const double feed = v.dot(hole.axis);
    const Eigen::Vector3d v_lateral = v - feed * hole.axis;
    Eigen::Vector3d force =
        -params_.lateral_stiffness * offset - params_.lateral_damping * v_lateral;
    // Cutting resistance: the wall pushes back with up to the threshold while the bit rests
    // (a static hold, so the tip does not creep in under a light push), plus feed damping.
    // The static part is modelled as a stiff spring against the deepest point reached.
    const double behind = hole.depth - depth;  // >= 0: how far the tip is back from the bottom
    double resist = 0.0;
    if (behind < 1e-3) {
      // The force is applied explicitly for one physics step: damping above m / dt would
      // reverse the feed within the step (and oscillate), so it is capped at half of that for
      // a light tool (the real arm's effective mass at the bit is > 10 kg, under the cap).
      const double cap = 0.5 * effective_mass(m, d, bit.body, p, hole.axis) / m->opt.timestep;
      resist =
          std::min(params_.thrust_threshold, params_.thrust_threshold * (1e-3 - behind) / 1e-3) +
          std::min(params_.feed_damping, cap) * std::max(feed, 0.0);
    }
    force -= resist * hole.axis;
    // Applied at the tip: xfrc_applied acts at the body's centre of mass.
    const Eigen::Vector3d com(d->xipos[3 * bit.body], d->xipos[3 * bit.body + 1],
                              d->xipos[3 * bit.body + 2]);
    const Eigen::Vector3d torque = (p - com).cross(force);
    for (int i = 0; i < 3; ++i) {
      f[i] = force(i);
      f[3 + i] = torque(i);
    }
    const auto k = static_cast<std::size_t>(bit.hole);
    if (reported_depth_.size() < holes.size()) reported_depth_.resize(holes.size(), 0.0);
    if (hole.depth - reported_depth_[k] >= kReportStep) {
      reported_depth_[k] = hole.depth;
      changed = true;
    }
  }
  return changed;
}

}  // namespace concert::sim
