#include "drill/paths.hpp"

#include <algorithm>
#include <cmath>

namespace concert::drill {
namespace {

bool is_base(const std::string& n) { return n == "base_x" || n == "base_y" || n == "base_yaw"; }

}  // namespace

PathSample sample_here(const std::vector<std::string>& names, const JointSample& s, const PathSample& towards) {
  PathSample here;
  for (std::size_t i = 0; i < names.size(); ++i) {
    const std::string& n = names[i];
    double v = 0.0;
    if (n == "base_yaw" && i < towards.position.size()) {
      const double planned = towards.position[i];
      v = planned + std::remainder(s.odometry[2] - planned, 2.0 * M_PI);
    } else if (is_base(n)) {
      v = s.odometry[n == "base_x" ? 0 : n == "base_y" ? 1 : 2];
    } else {
      const auto it = std::find(s.joints.names.begin(), s.joints.names.end(), n);
      if (it != s.joints.names.end()) v = s.joints.positions[static_cast<std::size_t>(it - s.joints.names.begin())];
    }
    here.position.push_back(v);
    here.velocity.push_back(0.0);
  }
  return here;
}

bool keep_base(const std::vector<std::string>& names, const PathSample& here, std::vector<PathSample>& path,
               double bound) {
  if (path.empty()) return false;
  if (bound > 0.0) {
    for (const PathSample& p : path) {
      for (std::size_t i = 0; i < names.size(); ++i) {
        if (!is_base(names[i])) continue;
        if (i >= p.position.size() || i >= here.position.size() || std::abs(p.position[i] - here.position[i]) > bound)
          return false;
      }
    }
  }
  for (PathSample& p : path) {
    for (std::size_t i = 0; i < names.size() && i < p.position.size(); ++i) {
      if (is_base(names[i]) && i < here.position.size()) {
        p.position[i] = here.position[i];
        if (i < p.velocity.size()) p.velocity[i] = 0.0;
      }
    }
  }
  return true;
}

double settle_time(const std::vector<std::string>& names, const PathSample& from, const PathSample& to,
                   const PathTiming& timing) {
  double t = timing.settle_min;
  for (std::size_t i = 0; i < names.size() && i < from.position.size() && i < to.position.size(); ++i) {
    const bool base = names[i] == "base_x" || names[i] == "base_y";
    const double speed = base ? timing.base_speed : timing.joint_speed;
    t = std::max(t, timing.speed_share * std::abs(to.position[i] - from.position[i]) / speed);
  }
  return t;
}

void append_reversed(std::vector<PathSample>& back, const Path& path, double& t, const PathTiming& timing) {
  t += timing.settle_min;
  const double end = path.samples.back().time;
  for (auto it = path.samples.rbegin(); it != path.samples.rend(); ++it) {
    PathSample sample = *it;
    sample.time = t + end - it->time;
    for (double& v : sample.velocity) v = -v;
    back.push_back(std::move(sample));
  }
  t += end;
}

std::vector<PathSample> return_path(const std::vector<Path>& chain, const JointSample& s, const PathTiming& timing) {
  std::vector<PathSample> back{sample_here(chain.front().names, s, chain.back().samples.back())};
  // Each path's end is the hole's posture, where the arm went back after its retract.
  double t = 0.0;
  for (auto path = chain.rbegin(); path != chain.rend(); ++path) append_reversed(back, *path, t, timing);
  // The holes' postures all taken with the base where it stands now (arm-alone postures, or a
  // base moved by less than base_kept): the way back keeps it there too.
  keep_base(chain.front().names, back.front(), back, timing.base_kept);
  return back;
}

Settle settle_path(const Path& p, const PathSample& here, const PathTiming& timing) {
  Settle out;
  out.samples = {here, p.samples.back()};
  const std::vector<double>& planned = p.samples.back().position;
  out.base_kept = keep_base(p.names, here, out.samples, timing.base_kept);
  if (out.base_kept) {
    double off = 0.0;
    for (std::size_t i = 0; i < p.names.size() && i < planned.size() && i < here.position.size(); ++i) {
      const double d = here.position[i] - planned[i];
      if (p.names[i] == "base_yaw") {
        out.base_turn = std::abs(d);
      } else if (p.names[i] == "base_x" || p.names[i] == "base_y") {
        off += d * d;
      }
    }
    out.base_off = std::sqrt(off);
  }
  PathSample& end = out.samples.back();
  end.time = settle_time(p.names, here, end, timing);
  for (double& v : end.velocity) v = 0.0;
  return out;
}

std::vector<PathSample> back_from_look(const Path& look, const Path& posture, const JointSample& s,
                                       const PathTiming& timing) {
  if (look.names != posture.names || look.samples.size() < 2) {
    return settle_path(posture, sample_here(posture.names, s, posture.samples.back()), timing).samples;
  }
  std::vector<PathSample> back{sample_here(look.names, s, look.samples.back())};
  double t = 0.0;
  append_reversed(back, look, t, timing);
  PathSample rest = posture.samples.back();  // where the look started from, at rest
  rest.time = back.back().time + settle_time(posture.names, back.back(), rest, timing);
  for (double& v : rest.velocity) v = 0.0;
  back.push_back(std::move(rest));
  keep_base(posture.names, back.front(), back, timing.base_kept);
  return back;
}

}  // namespace concert::drill
