#include "gui/allow_list.hpp"

#include <algorithm>
#include <array>

namespace concert::gui {

namespace {

// Operator commands: the safety panel, the robot page's homing/add-on customisation, drilling
// missions, navigation goals, surface finishing runs and transport modes. Motion commands (joint, Cartesian, base velocity, trajectories)
// and the simulator's commands are left out on purpose: services send those, not a tablet.
constexpr std::array kCommands{
    // Every signed-in client may stop the robot, whatever its role.
    OperatorCommand{"concert/safety/estop", "software e-stop: engage or release",
                    R"j({"source": "ESTOP_SOFTWARE"})j", true, Role::kViewer},
    OperatorCommand{"concert/safety/reset", "reset a latched safety stop",
                    R"j({"source": "concert gui ({origin})"})j", true},
    OperatorCommand{"concert/model/customisation", "homing postures and add-on choices", "{}", false,
                    Role::kEngineer},
    OperatorCommand{"concert/drill/mission", "start a drilling mission", "{}", false},
    OperatorCommand{"concert/drill/abort", "abort the drilling mission", "{}", false},
    OperatorCommand{"concert/nav/goal", "send the base to a pose", "{}", false},
    OperatorCommand{"concert/nav/cancel", "cancel the navigation goal", "{}", false},
    OperatorCommand{"concert/finish/command", "spray or sand a wall area, or abort the run",
                    R"j({"source": "concert gui ({origin})"})j", true},
    OperatorCommand{"concert/collab/command", "collaborative transport: a mode or action button",
                    R"j({"source": "gui", "direct": true})j", true},
    // The simulator's hot swap (what bolting other modules on is for the real robot); its other
    // command, a new world, stays with the tools.
    OperatorCommand{"concert/sim/command", "hot swap the simulated robot to an assembly",
                    R"j({"source": "concert gui ({origin})"})j", true, Role::kEngineer,
                    R"j({"kind": ["SIM_SWAP_ASSEMBLY"]})j"},
};

Json substitute(Json value, std::string_view origin) {
  if (value.is_string()) {
    std::string s = value.get<std::string>();
    const std::string key = "{origin}";
    for (auto pos = s.find(key); pos != std::string::npos; pos = s.find(key, pos + origin.size())) {
      s.replace(pos, key.size(), origin);
    }
    return s;
  }
  return value;
}

}  // namespace

std::span<const OperatorCommand> operator_commands() { return kCommands; }

const OperatorCommand* find_operator_command(std::string_view topic) {
  for (const auto& c : kCommands) {
    if (c.topic == topic) return &c;
  }
  return nullptr;
}

Json admit_command(std::string_view topic, const Json& data, std::string_view origin, int64_t now_ns) {
  const OperatorCommand* entry = find_operator_command(topic);
  if (entry == nullptr) {
    throw CommandRefused("'" + std::string(topic) +
                         "' is not an operator command (the GUI may command only the topics of "
                         "services/gui/src/core/allow_list.cpp)");
  }
  if (!data.is_object()) {
    throw CommandRefused("command on '" + std::string(topic) + "': data must be a JSON object, got " +
                         std::string(data.type_name()));
  }
  Json out = data;
  const Json only = Json::parse(entry->only_json);
  for (auto it = only.begin(); it != only.end(); ++it) {
    if (!out.contains(it.key())) {
      out[it.key()] = it.value().front();
    } else if (std::find(it.value().begin(), it.value().end(), out[it.key()]) == it.value().end()) {
      throw CommandRefused("command on '" + std::string(topic) + "': " + it.key() + " " + out[it.key()].dump() +
                           " is not allowed from the GUI (only " + it.value().dump() + ")");
    }
  }
  const Json fixed = Json::parse(entry->fixed_json);
  for (auto it = fixed.begin(); it != fixed.end(); ++it) out[it.key()] = substitute(it.value(), origin);
  if (entry->stamp && (!out.contains("stamp_ns") || out["stamp_ns"] == 0)) out["stamp_ns"] = now_ns;
  return out;
}

void check_role(std::string_view topic, Role role) {
  const OperatorCommand* entry = find_operator_command(topic);
  if (entry == nullptr) return;  // admit_command refuses it with the reason
  if (role < entry->role) {
    throw CommandRefused("role " + std::string(to_string(role)) + " may not command '" + std::string(topic) +
                         "' (" + std::string(entry->what) + "): it needs " + std::string(to_string(entry->role)) +
                         (entry->role == Role::kEngineer ? "" : " or engineer"));
  }
}

}  // namespace concert::gui
