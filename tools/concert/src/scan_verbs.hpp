#pragma once
#include <ostream>
#include <string>
#include <vector>

namespace concert::cli {

/// `concert scan show|publish ...`; args start after "scan". Returns the exit code.
int run_scan(const std::vector<std::string>& args, std::ostream& out, std::ostream& err);

}  // namespace concert::cli
