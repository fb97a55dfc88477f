#include "drill/placement.hpp"

#include <algorithm>
#include <cmath>
#include <sstream>

#include "drill/mission.hpp"

namespace concert::drill {

Eigen::Isometry3d placement_goal(const std::vector<DrillPoint>& holes,
                                 const std::optional<Eigen::Vector3d>& mark, double toward) {
  if (holes.empty()) throw DrillError("placement: no holes to place the base for");
  Eigen::Vector3d centre = Eigen::Vector3d::Zero();
  Eigen::Vector3d normal = Eigen::Vector3d::Zero();
  for (const DrillPoint& h : holes) {
    centre += h.frame.translation();
    normal += h.frame.linear().col(2);
  }
  centre /= static_cast<double>(holes.size());
  if (normal.norm() < 1e-6) throw DrillError("placement: the holes' normals cancel out");
  normal.normalize();
  if (std::abs(normal.z()) > 0.95)
    throw DrillError("placement: the holes face up or down (normal z " + std::to_string(normal.z()) + ")");
  Eigen::Isometry3d goal = Eigen::Isometry3d::Identity();
  // As the areas' frames (provisional_area, locate_area): x = up x normal, horizontal; y up
  // the surface.
  const Eigen::Vector3d x = Eigen::Vector3d::UnitZ().cross(normal).normalized();
  goal.linear().col(0) = x;
  goal.linear().col(1) = normal.cross(x);
  goal.linear().col(2) = normal;
  goal.translation() = centre;
  if (mark) {
    const Eigen::Vector3d d = *mark - centre;
    goal.translation() += toward * (d - normal * normal.dot(d));
  }
  return goal;
}

std::vector<std::size_t> reached_first(const std::vector<bool>& reached) {
  std::vector<std::size_t> order;
  for (const bool pass : {true, false}) {
    for (std::size_t i = 0; i < reached.size(); ++i) {
      if (reached[i] == pass) order.push_back(i);
    }
  }
  return order;
}

PlacementChoice::PlacementChoice(std::size_t holes, std::size_t draws)
    : holes_(holes), max_draws_(draws == 0 ? 1 : draws) {}

void PlacementChoice::standing(std::size_t reached) { standing_ = std::min(reached, holes_); }

void PlacementChoice::drawn(std::size_t reached, bool look) {
  drawn_.push_back({std::min(reached, holes_), look});
}

std::optional<std::size_t> PlacementChoice::best() const {
  std::optional<std::size_t> best;
  for (std::size_t i = 0; i < drawn_.size(); ++i) {
    if (!drawn_[i].look) continue;
    if (!best || drawn_[i].reached > drawn_[*best].reached) best = i;
  }
  return best;
}

PlacementChoice::Next PlacementChoice::next() const {
  if (!standing_) return Next::kCheckStanding;
  if (*standing_ >= holes_) return Next::kStand;
  const std::optional<std::size_t> b = best();
  if (b && drawn_[*b].reached >= holes_) return Next::kMove;
  if (drawn_.size() < max_draws_) return Next::kDraw;
  return b && drawn_[*b].reached > *standing_ ? Next::kMove : Next::kStand;
}

std::size_t PlacementChoice::chosen() const { return best().value_or(0); }

bool PlacementChoice::short_of_every_hole() const {
  return standing_ && next() == Next::kStand && *standing_ < holes_;
}

std::string PlacementChoice::summary() const {
  std::ostringstream s;
  s << "the arm alone reaches ";
  if (standing_)
    s << *standing_ << " of " << holes_ << " holes from where the base stands";
  else
    s << "(not checked) from where the base stands";
  for (std::size_t i = 0; i < drawn_.size(); ++i) {
    s << (i == 0 ? "; from the whole-body postures drawn: " : ", ") << drawn_[i].reached << " of "
      << holes_ << (drawn_[i].look ? " with" : " without") << " a look at the mark";
  }
  return s.str();
}

const char* to_string(Reach r) {
  switch (r) {
    case Reach::kReachable:
      return "reachable";
    case Reach::kUnreachable:
      return "unreachable";
    case Reach::kUnknown:
      break;
  }
  return "unknown";
}

ReachSurvey::ReachSurvey(std::size_t holes, std::size_t attempts, int tries)
    : attempts_(attempts), tries_(tries), states_(holes), verdicts_(holes) {
  if (attempts == 0 || tries < 1) throw DrillError("reach survey: needs at least one attempt and one try");
}

std::optional<std::size_t> ReachSurvey::next(std::size_t i) const {
  if (states_.at(i).decided) return std::nullopt;
  return states_[i].attempt;
}

void ReachSurvey::found(std::size_t i, const std::string& how) {
  if (states_.at(i).decided) return;
  states_[i].decided = true;
  verdicts_[i] = {Reach::kReachable, how};
}

void ReachSurvey::not_found(std::size_t i, const std::string& why) {
  State& s = states_.at(i);
  if (s.decided) return;
  if (++s.tried < tries_) return;
  s.tried = 0;
  if (++s.attempt < attempts_) return;
  s.decided = true;
  verdicts_[i] = {Reach::kUnreachable, why};
}

void ReachSurvey::unknown(std::size_t i, const std::string& why) {
  if (states_.at(i).decided) return;
  states_[i].decided = true;
  verdicts_[i] = {Reach::kUnknown, why};
}

bool ReachSurvey::done() const {
  return std::all_of(states_.begin(), states_.end(), [](const State& s) { return s.decided; });
}

std::string ReachSurvey::summary() const {
  std::size_t reachable = 0;
  std::string unreachable, unknown;
  for (std::size_t i = 0; i < verdicts_.size(); ++i) {
    const HoleReach& v = verdicts_[i];
    const std::string item = "hole " + std::to_string(i + 1) + " (" + v.why + ")";
    if (v.reach == Reach::kReachable) ++reachable;
    if (v.reach == Reach::kUnreachable) unreachable += (unreachable.empty() ? "" : ", ") + item;
    if (v.reach == Reach::kUnknown) unknown += (unknown.empty() ? "" : ", ") + item;
  }
  std::string out = std::to_string(reachable) + " of " + std::to_string(verdicts_.size()) +
                    (verdicts_.size() == 1 ? " hole reachable" : " holes reachable");
  if (!unreachable.empty()) out += "; unreachable: " + unreachable;
  if (!unknown.empty()) out += "; not judged: " + unknown;
  return out;
}

}  // namespace concert::drill
