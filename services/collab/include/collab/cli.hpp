#pragma once
// `concert collab ...` verbs (registered into the `concert` tool).

#include "concert/cli/cli.hpp"

namespace concert::collab {

/// Registers:
/// * `concert collab say "TEXT"`: sends a spoken/typed command ("hey concert follow me"; the
///   wake phrase is required) and prints the resulting state, or why it was ignored. Exit 0
///   when accepted, 1 when ignored or no service answered.
/// * `concert collab listen --wav FILE`: recognises the commands in a WAV file (PocketSphinx,
///   offline, utterances split at pauses), prints what was heard and the command (or why it was
///   rejected), and sends each command; `--dry-run` only recognises.
/// * `concert collab mode MODE`: teaching | autonomous | follow-me | stop (or an action: open,
///   close, lift, place), as the GUI's buttons do (no wake phrase).
/// * `concert collab status [--json]`: the state, the last command and its result.
void register_verbs(cli::Cli& concert);

}  // namespace concert::collab
