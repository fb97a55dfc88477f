#include "collab/command_parser.hpp"

#include <cctype>

namespace concert::collab {

std::vector<std::string> normalise_words(std::string_view text) {
  std::vector<std::string> words;
  std::string cur;
  for (char ch : text) {
    const auto u = static_cast<unsigned char>(ch);
    if (std::isalnum(u) || ch == '\'') {
      cur += static_cast<char>(std::tolower(u));
    } else if (!cur.empty()) {
      words.push_back(std::move(cur));
      cur.clear();
    }
  }
  if (!cur.empty()) words.push_back(std::move(cur));
  return words;
}

const char* command_phrase(Command c) { return command_name(c); }

ParsedCommand parse_command(std::string_view text) {
  const auto words = normalise_words(text);
  if (words.empty()) return {std::nullopt, "empty command"};
  // The last "hey concert": speech before it (another sentence) does not matter.
  std::optional<std::size_t> wake;
  for (std::size_t i = 0; i + 1 < words.size(); ++i) {
    if (words[i] == "hey" && words[i + 1] == "concert") wake = i;
  }
  if (!wake) return {std::nullopt, "no wake phrase \"hey concert\" in \"" + std::string(text) + "\""};
  std::string rest;
  for (std::size_t i = *wake + 2; i < words.size(); ++i) {
    if (!rest.empty()) rest += ' ';
    rest += words[i];
  }
  if (rest.empty()) return {std::nullopt, "wake phrase without a command"};
  for (Command c : kAllCommands) {
    if (rest == command_phrase(c)) return {c, {}};
  }
  return {std::nullopt, "unknown command \"" + rest +
                            "\" (expected teaching, autonomous, follow me, stop, open, close, lift or place)"};
}

}  // namespace concert::collab
