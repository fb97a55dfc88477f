#include "collab/state_machine.hpp"

#include <cctype>

namespace concert::collab {

const char* mode_name(Mode m) {
  switch (m) {
    case Mode::kTeaching:
      return "teaching";
    case Mode::kAutonomous:
      return "autonomous";
    case Mode::kFollowMe:
      return "follow-me";
    case Mode::kStop:
      return "stop";
  }
  return "?";
}

const char* sub_state_name(SubState s) {
  switch (s) {
    case SubState::kNone:
      return "";
    case SubState::kGeneral:
      return "general";
    case SubState::kOpen:
      return "open";
    case SubState::kClose:
      return "close";
    case SubState::kHold:
      return "hold";
    case SubState::kLift:
      return "lift";
    case SubState::kPlace:
      return "place";
  }
  return "?";
}

const char* command_name(Command c) {
  switch (c) {
    case Command::kTeaching:
      return "teaching";
    case Command::kAutonomous:
      return "autonomous";
    case Command::kFollowMe:
      return "follow me";
    case Command::kStop:
      return "stop";
    case Command::kOpen:
      return "open";
    case Command::kClose:
      return "close";
    case Command::kLift:
      return "lift";
    case Command::kPlace:
      return "place";
  }
  return "?";
}

std::string state_name(const State& s) {
  std::string out = mode_name(s.mode);
  if (s.sub != SubState::kNone) {
    out += '/';
    out += sub_state_name(s.sub);
  }
  return out;
}

std::optional<Mode> parse_mode(std::string_view name) {
  std::string n;
  for (char ch : name) n += static_cast<char>(std::tolower(static_cast<unsigned char>(ch)));
  if (n == "teaching") return Mode::kTeaching;
  if (n == "autonomous") return Mode::kAutonomous;
  if (n == "follow-me" || n == "follow_me" || n == "followme" || n == "follow me") return Mode::kFollowMe;
  if (n == "stop") return Mode::kStop;
  return std::nullopt;
}

Transition StateMachine::ignore(Command c, std::string why) const {
  return Transition{false, c, state_, state_, std::move(why)};
}

Transition StateMachine::go(Command c, State to) {
  Transition t{true, c, state_, to, {}};
  if (to == state_) {
    t.accepted = false;
    t.reason = std::string("already in ") + state_name(state_);
    return t;
  }
  state_ = to;
  return t;
}

Transition StateMachine::apply(Command c) {
  if (estop_) return ignore(c, std::string(command_name(c)) + " is ignored: the e-stop is active");
  const Mode m = state_.mode;
  const std::string in = std::string(" is ignored in ") + mode_name(m);
  switch (c) {
    case Command::kTeaching:
      if (m == Mode::kTeaching) return ignore(c, "already in teaching");
      return go(c, {Mode::kTeaching, SubState::kGeneral});
    case Command::kAutonomous:
      if (m == Mode::kAutonomous) return ignore(c, "already in autonomous");
      return go(c, {Mode::kAutonomous, SubState::kHold});
    case Command::kFollowMe:
      return go(c, {Mode::kFollowMe, SubState::kNone});
    case Command::kStop:
      return go(c, {Mode::kStop, SubState::kNone});
    case Command::kOpen:
      if (m == Mode::kTeaching) return go(c, {Mode::kTeaching, SubState::kOpen});
      if (m == Mode::kStop) return ignore(c, "open" + in + ": say teaching first");
      return ignore(c, "open" + in + ": the gripper may hold the load (only in teaching)");
    case Command::kClose:
      if (m == Mode::kTeaching) return go(c, {Mode::kTeaching, SubState::kClose});
      return ignore(c, "close" + in + ": gripper actions are taught (only in teaching)");
    case Command::kLift:
      if (m == Mode::kTeaching || m == Mode::kAutonomous) return go(c, {Mode::kAutonomous, SubState::kLift});
      return ignore(c, "lift" + in + ": only from teaching or autonomous");
    case Command::kPlace:
      if (m == Mode::kFollowMe || m == Mode::kAutonomous) return go(c, {Mode::kAutonomous, SubState::kPlace});
      return ignore(c, "place" + in + ": only from follow-me or autonomous");
  }
  return ignore(c, "unknown command");
}

Transition StateMachine::set_estop(bool active) {
  if (!active) {
    const bool was = estop_;
    estop_ = false;
    Transition t{false, Command::kStop, state_, state_, was ? "e-stop released: still in stop" : "e-stop was not active"};
    return t;
  }
  estop_ = true;
  Transition t{state_.mode != Mode::kStop, Command::kStop, state_, {Mode::kStop, SubState::kNone}, {}};
  if (!t.accepted) t.reason = "already in stop";
  state_ = t.to;
  return t;
}

}  // namespace concert::collab
