#pragma once
// Spoken or typed text -> a command of the state machine. The wake phrase "hey concert" is
// required: the words after its last occurrence must be exactly one command phrase ("hey
// concert, follow me"). Anything else (no wake phrase, an unknown or extra word, the wake
// phrase alone) is rejected with the reason. Case and punctuation do not matter. Plain C++.

#include <optional>
#include <string>
#include <string_view>
#include <vector>

#include "collab/state_machine.hpp"

namespace concert::collab {

struct ParsedCommand {
  std::optional<Command> command;  ///< set when the text is a valid command
  std::string reason;              ///< why not, when unset
};

/// Lower-case words of `text` (letters, digits and apostrophes; everything else separates).
std::vector<std::string> normalise_words(std::string_view text);

/// Parses "hey concert <command>"; see the file comment.
ParsedCommand parse_command(std::string_view text);

/// The command phrase of each command ("follow me" for kFollowMe), as it is spoken.
const char* command_phrase(Command c);

}  // namespace concert::collab
