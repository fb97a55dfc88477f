#include "concert/topology/port_order.hpp"
#include "concert/topology/types.hpp"

namespace concert::topology {

std::optional<ModuleKind> module_kind_from_mod_type(int32_t mod_type) {
  switch (mod_type) {
    case 1: return ModuleKind::kJoint;
    case 2: return ModuleKind::kHub;
    case 3: return ModuleKind::kEndEffector;
    case 4: return ModuleKind::kLink;
    case 5: return ModuleKind::kWheel;
    case 6: return ModuleKind::kBaseLink;
    default: return std::nullopt;
  }
}

std::string to_string(ModuleKind kind) {
  switch (kind) {
    case ModuleKind::kJoint: return "joint";
    case ModuleKind::kHub: return "hub";
    case ModuleKind::kEndEffector: return "end_effector";
    case ModuleKind::kLink: return "link";
    case ModuleKind::kWheel: return "wheel";
    case ModuleKind::kBaseLink: return "base_link";
    case ModuleKind::kUnknown:
      return "unknown";
  }
  return "unknown";
}

std::string to_string(const EscIdentity& identity) {
  return "(mod_type " + std::to_string(identity.mod_type) + ", mod_id " +
         std::to_string(identity.mod_id) + ", mod_size " + std::to_string(identity.mod_size) +
         ", mod_rev " + std::to_string(identity.mod_rev) + ")";
}

std::string TreeIssue::text() const {
  return position > 0 ? "slave " + std::to_string(position) + ": " + message : message;
}

bool ModuleTree::has_errors() const { return count(TreeIssue::Severity::kError) > 0; }

std::size_t ModuleTree::count(TreeIssue::Severity severity) const {
  std::size_t n = 0;
  for (const auto& issue : issues) n += issue.severity == severity ? 1 : 0;
  return n;
}

std::vector<int32_t> ModuleTree::unknown_modules() const {
  std::vector<int32_t> out;
  for (const auto& m : modules) {
    if (!m.known) out.push_back(m.index);
  }
  return out;
}

std::array<int32_t, 4> frame_order(PortOrder order) {
  if (order == PortOrder::kNumeric0123) return {0, 1, 2, 3};
  return {0, 3, 1, 2};
}

std::optional<PortOrder> parse_port_order(std::string_view text) {
  if (text == "0312") return PortOrder::kReal0312;
  if (text == "0123") return PortOrder::kNumeric0123;
  return std::nullopt;
}

std::string to_string(PortOrder order) {
  return order == PortOrder::kNumeric0123 ? "0123" : "0312";
}

}  // namespace concert::topology
