#pragma once
// `concert security ...` verbs, for the concert tool:
//   security init DIR [--force] [--days N]   creates the PKI (pki.hpp) in DIR; refuses to
//                                            replace one without --force; prints each file
//   security table [--json]                  who may publish what (table.hpp)
//   security check DIR [--identity NAME]     checks the identities' files (signatures, dates)
// No DDS: they only write and read files.

#include "concert/cli/cli.hpp"

namespace concert::security {

/// Registers `concert security init|table|check` into `concert`. Exit codes: 0 done, 1 failure
/// (a PKI already there, a file that cannot be written or does not check), 2 bad command line.
void register_verbs(cli::Cli& concert);

}  // namespace concert::security
