#pragma once
// Small helpers to read typed fields from yaml-cpp nodes with messages naming file and field.

#include <cstdint>
#include <limits>
#include <optional>
#include <string>

#include <yaml-cpp/yaml.h>

namespace concert::topology::detail {

/// "line 12" of a node's mark, or "" when unknown.
inline std::string where(const YAML::Node& node) {
  const YAML::Mark mark = node.Mark();
  if (mark.line < 0) return "";
  return " (line " + std::to_string(mark.line + 1) + ")";
}

/// Reads an integer scalar; throws Error naming `context` and the value.
template <class Error>
int64_t as_int(const YAML::Node& node, const std::string& context) {
  if (!node.IsScalar()) throw Error(context + ": expected an integer" + where(node));
  try {
    return node.as<int64_t>();
  } catch (const YAML::Exception&) {
    throw Error(context + ": '" + node.Scalar() + "' is not an integer" + where(node));
  }
}

/// Reads an int32 field of a map; empty if absent, throws Error if present and invalid.
template <class Error>
std::optional<int32_t> opt_int32(const YAML::Node& map, const char* field,
                                 const std::string& context) {
  const YAML::Node node = map[field];
  if (!node || node.IsNull()) return std::nullopt;
  const int64_t value = as_int<Error>(node, context + "." + field);
  if (value < std::numeric_limits<int32_t>::min() || value > std::numeric_limits<int32_t>::max()) {
    throw Error(context + "." + field + ": " + std::to_string(value) + " is out of range" +
                where(node));
  }
  return static_cast<int32_t>(value);
}

/// Reads a required int32 field of a map.
template <class Error>
int32_t req_int32(const YAML::Node& map, const char* field, const std::string& context) {
  const auto value = opt_int32<Error>(map, field, context);
  if (!value) throw Error(context + ": missing field '" + field + "'" + where(map));
  return *value;
}

}  // namespace concert::topology::detail
