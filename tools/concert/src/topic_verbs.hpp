#pragma once
#include <ostream>
#include <string>
#include <vector>

namespace concert::cli {

/// `concert topic list|info|echo|hz ...`; args start after "topic". Returns the exit code.
int run_topic(const std::vector<std::string>& args, std::ostream& out, std::ostream& err);

}  // namespace concert::cli
