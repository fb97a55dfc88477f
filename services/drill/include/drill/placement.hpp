#pragma once
// Where the base stands while an area's holes are drilled. Plain C++, no DDS.
//
// The paper drills "all the drilling points it is able to detect" from the configuration the
// area's approach reached (section 5.4.2). That approach puts the drill camera 0.6 m from the
// wall, the bit about 0.4 m short of it, and from there morphology A's arm alone reaches none of
// a 60 cm ArUco row's holes (self collision and torque). Moving the whole body for each hole
// drifts the wheel odometry 10-60 mm a move, and an ArUco pattern is drilled by the kinematics
// alone: every hole then depends on the camera being turned back onto the marker after its
// move, which from some postures it cannot be (the hole then 12-19 mm off), and every move is
// another chance for the arm's path to meet the wall.
//
// So an area of several holes gets one base placement before its first hole: whole-body
// postures are drawn with the bit a little further out than a hole's in front of the holes
// (kPlacementDraws, placement_goal()), and from each one the arm alone is asked for every hole's drilling posture and for a look at
// the area's mark (all planned, none executed). The base moves once, to a posture from which
// the arm alone reaches every hole and the camera the mark, or it stays. PlacementChoice keeps
// the tally and says which.

#include <Eigen/Geometry>
#include <cstddef>
#include <optional>
#include <string>
#include <vector>

#include "drill/ports.hpp"

namespace concert::drill {

/// One whole-body posture drawn for a placement: the bit `out` [m] further from the wall than a
/// hole's drilling distance, aimed at the holes' centre moved `toward` (a fraction) of the way to
/// the area's mark. A bit that reaches the wall from 15-20 cm further out leaves the arm the room
/// to swing across a 60 cm row. On morphology A at scenario 3's row at 1.5 m, the marker
/// 15 cm above it (the planner's service budgets, the arm alone then asked for each hole 0, 3
/// and 7 cm further out): the bit at the drilling distance on the row's centre gives
/// placements reaching 1-3 of the 4 holes, 10 cm out 1-3, 20 cm out 4 of 4 (3 draws of 3);
/// aimed halfway to the marker, 15 cm out 4 of 4, 20 cm out 3 of 4, 25 cm out no posture. The
/// planner's posture search starts from the robot's posture, so the same request drawn again
/// mostly gives the same posture: each draw asks for another goal.
struct PlacementDraw {
  double out{0.0};
  double toward{0.0};
};
inline constexpr PlacementDraw kPlacementDraws[] = {{0.20, 0.0}, {0.15, 0.5}, {0.20, 0.5}};

/// The frame a placement's posture is drawn for: origin at the centroid of the holes' origins
/// (world frame) moved `toward` of the way to `mark` along the wall (the part along the holes'
/// normal left out), z along their mean normal, x horizontal, y up (as the holes' frames).
/// Throws DrillError for no holes, or normals that cancel out or point up or down (|z| > 0.95).
Eigen::Isometry3d placement_goal(const std::vector<DrillPoint>& holes,
                                 const std::optional<Eigen::Vector3d>& mark = std::nullopt,
                                 double toward = 0.0);

/// The order to drill an area's holes from a placement: those `reached` by the arm alone first,
/// then the others, each in the order they came (their pattern's). A hole the arm cannot reach
/// moves the base again, and with no look at the mark possible after that move, the holes after
/// it carry its drift (18 mm along the row on the pattern test).
std::vector<std::size_t> reached_first(const std::vector<bool>& reached);

/// The tally of an area's placement: how many of its holes the arm alone reaches from where the
/// base stands and from each posture drawn, and whether the camera can be turned onto the
/// area's mark from it; and what to do next.
class PlacementChoice {
 public:
  enum class Next {
    kCheckStanding,  ///< ask how many holes the arm alone reaches from where the base stands
    kDraw,           ///< draw (another) whole-body posture and check it
    kStand,          ///< drill from where the base stands
    kMove,           ///< move to drawn posture chosen()
  };

  /// `holes`: the area's holes to drill (>= 1); `draws`: postures drawn at most (>= 1).
  PlacementChoice(std::size_t holes, std::size_t draws);

  /// From where the base stands the arm alone reaches `reached` holes. (The camera needs no
  /// look there: the area's marks were just detected from it.)
  void standing(std::size_t reached);
  /// The next drawn posture: `reached` holes by the arm alone from it, and whether the camera
  /// can be turned onto the mark from it. A draw that found no posture counts with 0, false.
  void drawn(std::size_t reached, bool look);

  /// Standing first; a drawn posture that reaches every hole with a look is taken at once;
  /// after every draw, the drawn posture with a look reaching the most holes (the first of
  /// equals) when it reaches more than standing does, else standing. A drawn posture without a
  /// look is never taken: after its move the holes would be drilled where odometry puts them.
  [[nodiscard]] Next next() const;
  /// The drawn posture to move to (its index among the draws) when next() is kMove.
  [[nodiscard]] std::size_t chosen() const;
  /// The tally is complete and the base would stay where it stands without the arm alone
  /// reaching every hole from there: worth a placement again with a lighter thrust checked.
  /// (Checked with the full thrust, the demo robot's arm holds it from no posture in front of
  /// its wall's pattern, nor morphology A's below 1.2 m; those holes are drilled at about half
  /// the thrust, and without a placement at that thrust each of them moves the whole body and
  /// is drilled where odometry puts it, centimetres off.)
  [[nodiscard]] bool short_of_every_hole() const;
  [[nodiscard]] std::size_t draws() const { return drawn_.size(); }
  /// For the log: "the arm alone reaches 0 of 4 holes from where the base stands; drawn: 4 of
  /// 4 with a look, ...".
  [[nodiscard]] std::string summary() const;

 private:
  struct Drawn {
    std::size_t reached{0};
    bool look{false};
  };
  [[nodiscard]] std::optional<std::size_t> best() const;
  std::size_t holes_;
  std::size_t max_draws_;
  std::optional<std::size_t> standing_;
  std::vector<Drawn> drawn_;
};

/// Whether each of an area's holes can be drilled, asked of the planner before anything moves
/// for them: per hole, whole-body postures (the base anywhere) of a list of attempts from the
/// full thrust to the most lenient (Params::reach.attempts), each asked up to `tries` times, as
/// the planner's posture search is randomised and one failure is no verdict. A hole is reachable
/// at the first attempt answered with a posture; unreachable once every attempt failed to find
/// one, with the last failure's reason; unknown when the planner could not judge (a refused
/// request, another model): such a hole is drilled as if never asked.
class ReachSurvey {
 public:
  /// `holes` >= 0, `attempts` >= 1, `tries` >= 1.
  ReachSurvey(std::size_t holes, std::size_t attempts, int tries);

  /// The attempt to ask for hole `i` next; none once its verdict is in.
  [[nodiscard]] std::optional<std::size_t> next(std::size_t i) const;
  /// Hole `i`'s current attempt found a posture; `how` names the attempt ("at full thrust").
  void found(std::size_t i, const std::string& how);
  /// Hole `i`'s current attempt found none (`why`: the planner's reason): the same attempt
  /// again until its tries are spent, then the next attempt.
  void not_found(std::size_t i, const std::string& why);
  /// The planner could not judge hole `i` (`why`): its verdict is unknown.
  void unknown(std::size_t i, const std::string& why);

  [[nodiscard]] bool done() const;
  [[nodiscard]] const std::vector<HoleReach>& verdicts() const { return verdicts_; }
  /// For the log and the report: "3 of 4 holes reachable; unreachable: hole 2 (no posture: ...)".
  [[nodiscard]] std::string summary() const;

 private:
  struct State {
    std::size_t attempt{0};
    int tried{0};
    bool decided{false};
  };
  std::size_t attempts_;
  int tries_;
  std::vector<State> states_;
  std::vector<HoleReach> verdicts_;
};

}  // namespace concert::drill
