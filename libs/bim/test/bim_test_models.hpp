#pragma once
// The shared IFC files, each imported once per test binary.

#include <fstream>
#include <map>
#include <regex>
#include <sstream>
#include <string>

#include "concert/bim/model.hpp"

namespace concert::bim::test_models {

inline std::string bim_file(const std::string& name) {
  return std::string(CONCERT_SHARED_DATA) + "/bim/" + name;
}

inline const BimModel& shared_model(const std::string& name) {
  static std::map<std::string, BimModel> models;
  auto it = models.find(name);
  if (it == models.end()) it = models.emplace(name, load_ifc(bim_file(name))).first;
  return it->second;
}

inline std::string file_text(const std::string& path) {
  std::ifstream in(path);
  std::stringstream s;
  s << in.rdbuf();
  return s.str();
}

/// How many instances of the IFC entity `upper_type` (e.g. "IFCWALLSTANDARDCASE") the file has:
/// the truth the import is checked against.
inline int count_entities(const std::string& text, const std::string& upper_type) {
  const std::regex re("=\\s*" + upper_type + "\\(");
  return static_cast<int>(
      std::distance(std::sregex_iterator(text.begin(), text.end(), re), std::sregex_iterator()));
}

}  // namespace concert::bim::test_models
