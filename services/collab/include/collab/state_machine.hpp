#pragma once
// The collaborative transportation task's state machine (paper section 5.5, Fig. 12) and the
// command words that drive it. Plain C++, no DDS.
//
// States: teaching (sub-states general, open, close), autonomous (sub-states hold, lift, place),
// follow-me, stop. Commands carry the names of the states and actions they lead to. The table
// (services/collab/README.md, "State machine"):
//
//   command     | teaching          | autonomous        | follow-me         | stop
//   ------------+-------------------+-------------------+-------------------+-----------------
//   teaching    | ignored (already) | teaching/general  | teaching/general  | teaching/general
//   autonomous  | autonomous/hold   | ignored (already) | autonomous/hold   | autonomous/hold
//   follow me   | follow-me         | follow-me         | ignored (already) | follow-me
//   stop        | stop              | stop              | stop              | ignored (already)
//   open        | teaching/open     | ignored (drop)    | ignored (drop)    | ignored
//   close       | teaching/close    | ignored           | ignored           | ignored
//   lift        | autonomous/lift * | autonomous/lift   | ignored           | ignored
//   place       | ignored           | autonomous/place  | autonomous/place *| ignored
//
// (*: the two shortcuts of the paper, one command switches the state and starts the action.)
// A command that would re-enter the sub-state it is in (open when open) is ignored as
// "already". The e-stop forces stop from anywhere; while it is active every command is ignored.

#include <array>
#include <optional>
#include <string>
#include <string_view>

namespace concert::collab {

/// The four main modes of Fig. 12.
enum class Mode { kTeaching, kAutonomous, kFollowMe, kStop };

/// Sub-states: teaching has general/open/close, autonomous has hold/lift/place; follow-me and
/// stop have none (kNone).
enum class SubState { kNone, kGeneral, kOpen, kClose, kHold, kLift, kPlace };

/// The eight commands (state and action names of Fig. 12).
enum class Command { kTeaching, kAutonomous, kFollowMe, kStop, kOpen, kClose, kLift, kPlace };

inline constexpr std::array<Command, 8> kAllCommands{Command::kTeaching, Command::kAutonomous,
                                                     Command::kFollowMe, Command::kStop,
                                                     Command::kOpen,     Command::kClose,
                                                     Command::kLift,     Command::kPlace};

struct State {
  Mode mode{Mode::kStop};
  SubState sub{SubState::kNone};
  friend bool operator==(const State&, const State&) = default;
};

/// What one command did: accepted (the state changed, `to` differs from `from`) or ignored
/// with the reason ("open is ignored in follow-me: the gripper holds the load").
struct Transition {
  bool accepted{false};
  Command command{Command::kStop};
  State from;
  State to;
  std::string reason;  ///< empty when accepted
};

const char* mode_name(Mode m);          ///< "teaching", "autonomous", "follow-me", "stop"
const char* sub_state_name(SubState s); ///< "", "general", "open", "close", "hold", "lift", "place"
const char* command_name(Command c);    ///< "teaching", "autonomous", "follow me", "stop", ...
std::string state_name(const State& s); ///< "teaching/open", "follow-me", "stop"

/// Mode by name ("teaching", "autonomous", "follow-me" or "follow_me", "stop"), or nullopt.
std::optional<Mode> parse_mode(std::string_view name);

/// Fig. 12. Starts in stop: a freshly started service moves nothing until told (the task then
/// begins with "teaching", as in the paper's experiment).
class StateMachine {
 public:
  StateMachine() = default;

  const State& state() const { return state_; }
  bool estop_active() const { return estop_; }

  /// Applies a command; never throws. Ignored commands leave the state untouched.
  Transition apply(Command c);

  /// The e-stop: active forces stop (a Transition from the old state, accepted when the state
  /// changed) and ignores every command until released; releasing leaves the machine in stop.
  Transition set_estop(bool active);

 private:
  Transition ignore(Command c, std::string why) const;
  Transition go(Command c, State to);

  State state_{};
  bool estop_{false};
};

}  // namespace concert::collab
