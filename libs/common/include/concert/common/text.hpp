#pragma once
// Text helpers shared by the services, the tools and the tests.

#include <filesystem>
#include <string>
#include <string_view>
#include <vector>

namespace concert {

/// The items of `items` (any range of things convertible to std::string_view) separated by
/// `separator`; "" for no items.
template <class Range>
std::string join(const Range& items, std::string_view separator = ", ") {
  std::string out;
  bool first = true;
  for (const auto& item : items) {
    if (!first) out += separator;
    out += std::string_view(item);
    first = false;
  }
  return out;
}

/// The pieces of `text` between `separator` characters, empty pieces left out
/// ("a,,b," -> {"a", "b"}).
std::vector<std::string> split(std::string_view text, char separator = ',');

/// The whole content of `file`. Throws std::runtime_error "`what` file 'FILE' cannot be opened"
/// when it cannot be read (`what` e.g. "parameters", "world").
std::string read_file(const std::filesystem::path& file, std::string_view what = "the");

}  // namespace concert
