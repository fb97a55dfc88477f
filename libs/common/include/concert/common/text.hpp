#pragma once
// Text helpers shared by the services, the tools and the tests.

#include <cstddef>
#include <filesystem>
#include <optional>
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

/// Index of the first byte of `text` that does not begin a valid UTF-8 character (a stray
/// continuation byte, a character cut short, an overlong form, a surrogate, a code point above
/// U+10FFFF); nullopt for valid UTF-8.
std::optional<std::size_t> invalid_utf8_at(std::string_view text);

/// Index of the first control character of `text` that YAML does not allow in a document (its
/// c-printable set: every C0 control but tab, line feed and carriage return, and DEL); nullopt
/// when there is none. A NUL in a key reads into a name that yaml-cpp writes back unreadable.
std::optional<std::size_t> yaml_control_character_at(std::string_view text);

/// The whole content of `file`. Throws std::runtime_error "`what` file 'FILE' cannot be opened"
/// when it cannot be read (`what` e.g. "parameters", "world").
std::string read_file(const std::filesystem::path& file, std::string_view what = "the");

}  // namespace concert
