#pragma once
// THE list of topics an operator may command from the browser (one place): everything else is
// read-only for the GUI. Each entry may pin fields the browser must not choose (the e-stop's
// source is always the software stop; a reset names the gateway and the client that asked).

#include <nlohmann/json.hpp>
#include <span>
#include <stdexcept>
#include <string>
#include <string_view>

#include "gui/auth.hpp"

namespace concert::gui {

using Json = nlohmann::ordered_json;

/// One commandable topic.
struct OperatorCommand {
  std::string_view topic;  ///< catalogue topic name
  std::string_view what;   ///< why an operator sends it (shown in the app and the log)
  /// Field -> value forced into every command ("{origin}" in a string value is replaced by
  /// the client's address), whatever the browser sent.
  std::string_view fixed_json = "{}";
  bool stamp = false;  ///< set `stamp_ns` to the gateway's clock when the browser left it 0/out
  Role role = Role::kOperator;  ///< the least role that may send it
  /// Field -> the values the browser may give it (a JSON array); a field left out gets the
  /// first. E.g. the simulator's command: hot swaps only, never a new world.
  std::string_view only_json = "{}";
};

/// Raised for a command the allow-list refuses; the message names the topic and why.
class CommandRefused : public std::runtime_error {
 public:
  using std::runtime_error::runtime_error;
};

/// Every operator-commandable topic.
std::span<const OperatorCommand> operator_commands();

/// The entry of `topic`, or nullptr when the browser may not command it.
const OperatorCommand* find_operator_command(std::string_view topic);

/// The sample to publish for a browser's command: `data` (a JSON object, fields may be left out)
/// with the entry's fixed fields and stamp applied. Throws CommandRefused when `topic` is not on
/// the list, `data` is not an object, or a field has a value the entry does not allow.
Json admit_command(std::string_view topic, const Json& data, std::string_view origin, int64_t now_ns);

/// Throws CommandRefused unless `role` may send `topic` (naming the role it needs).
void check_role(std::string_view topic, Role role);

}  // namespace concert::gui
