#pragma once
// Reading the text of an input file (a catalogue, a scan, an assembly) and parsing it as YAML,
// with errors of the reader's own type that name the file. Header-only; the YAML part needs
// yaml-cpp, which every user of it links already.

#include <filesystem>
#include <fstream>
#include <sstream>
#include <string>
#include <string_view>

#include <yaml-cpp/yaml.h>

namespace concert {

/// The whole content of `file`. Throws Error("FILE: cannot open WHAT") when it cannot be read,
/// `what` naming the kind of file (e.g. "the scan file").
template <class Error>
std::string read_text(const std::filesystem::path& file, std::string_view what) {
  std::ifstream in(file);
  if (!in) throw Error(file.string() + ": cannot open " + std::string(what));
  std::ostringstream text;
  text << in.rdbuf();
  return text.str();
}

/// The YAML document in `text`. Throws Error("SOURCE: not valid YAML: <yaml-cpp's message>"),
/// `source` naming where the text comes from (usually its file).
template <class Error>
YAML::Node parse_yaml(std::string_view text, const std::string& source) {
  try {
    return YAML::Load(std::string(text));
  } catch (const YAML::Exception& e) {
    throw Error(source + ": not valid YAML: " + e.what());
  }
}

}  // namespace concert
