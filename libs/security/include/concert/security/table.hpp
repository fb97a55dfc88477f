#pragma once
// THE table of who may publish what: the identities of the stack (one per service, one for the
// operator's tools) and, for every catalogue topic, the identities allowed to write it. The
// permissions documents of `concert security init` are generated from it and nothing else; every
// identity may read every topic. No DDS includes: plain data.

#include <span>
#include <string>
#include <string_view>
#include <vector>

namespace concert::security {

/// The identity of the operator's tools (every `concert` verb, unless told otherwise).
inline constexpr std::string_view kOperator = "operator";

/// Every identity, services first, then the operator.
std::span<const std::string_view> identities();

/// True for the identity of a service (its participant name, e.g. "robot"), false for the
/// operator and for names that are no identity.
bool is_service_identity(std::string_view name);

/// True for any identity of identities().
bool is_identity(std::string_view name);

/// One row of the table: a topic and the identities that may write it.
struct WriteRule {
  std::string_view topic;
  std::span<const std::string_view> writers;
  std::string_view why;  ///< one line: the rule behind the row
};

/// The table, in catalogue order.
std::span<const WriteRule> write_rules();

/// The identities that may write `topic` (empty for a topic the table does not name: nobody).
std::vector<std::string_view> writers_of(std::string_view topic);

/// True when `identity` may write `topic`.
bool may_write(std::string_view identity, std::string_view topic);

/// The topics `identity` may write, in table order.
std::vector<std::string_view> topics_written_by(std::string_view identity);

}  // namespace concert::security
