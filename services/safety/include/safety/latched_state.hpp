#pragma once
// The part of the safety service's state that a restart of the service must not lose: a
// latched stop and its causes, the e-stop inputs engaged, and the service instances watched
// (each with the process it was heard from). The service keeps it in a file
// (`concert_safety --state FILE`): rewritten on every change, read at start.

#include <map>
#include <string>
#include <vector>

namespace concert::safety {

enum class Mode { kRunning, kStopped };

/// The six e-stop inputs of the CONCERT base (paper section 3): four corner buttons, the
/// wireless receiver, and a software stop. Same order as msg::EStopSource.
enum class EStopSource {
  kButtonFrontLeft,
  kButtonFrontRight,
  kButtonRearLeft,
  kButtonRearRight,
  kWireless,
  kSoftware
};
inline constexpr std::size_t kEStopSourceCount = 6;

struct LatchedState {
  Mode mode = Mode::kRunning;
  std::vector<std::string> causes;      ///< oldest first, as SafetyStatus::causes
  std::vector<std::string> cause_keys;  ///< one per cause (what repeats the same cause)
  std::vector<EStopSource> engaged;     ///< e-stop inputs engaged
  /// "service@host" -> the process it was heard from (opaque; "" = not known).
  std::map<std::string, std::string> watched;
  bool operator==(const LatchedState&) const = default;
};

/// The state as YAML (the file's content).
std::string to_yaml(const LatchedState& state);
/// Reads the YAML of to_yaml(); throws config::ConfigError naming `origin`, the key and the
/// line when it is not such a state.
LatchedState parse_latched_state(const std::string& yaml, const std::string& origin);
/// Reads `file` (parse_latched_state); throws config::ConfigError when it cannot be read.
LatchedState load_latched_state(const std::string& file);
/// Writes `state` over `file` through a temporary file and a rename (a reader sees the old
/// state or the new, never half of one); throws std::runtime_error naming the file.
void save_latched_state(const std::string& file, const LatchedState& state);

}  // namespace concert::safety
