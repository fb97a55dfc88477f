// Network graph chi from the open-port registers: the linear reconstruction used by the
// service and the paper's Algorithms 1 and 2 as reference.
#include <algorithm>
#include <bit>
#include <sstream>

#include "concert/topology/reconstruction.hpp"

namespace concert::topology {
namespace {


std::string mask_text(uint8_t mask) {
  std::string bits = "0b";
  for (int bit = 3; bit >= 0; --bit) bits += (mask >> bit) & 1U ? '1' : '0';
  return bits;
}

int32_t open_count(const EscSlave& s) { return std::popcount(static_cast<unsigned>(s.active_ports)); }

/// Open downstream ports (1..3) of a slave in frame order; returns how many.
int32_t downstream_ports(const EscSlave& s, const std::array<int32_t, 4>& order,
                         std::array<int32_t, 3>& out) {
  int32_t n = 0;
  for (std::size_t k = 1; k < 4; ++k) {
    if ((s.active_ports >> order[k]) & 1U) out[static_cast<std::size_t>(n++)] = order[k];
  }
  return n;
}

std::string no_parent_message() {
  return "no earlier slave has a free open port for it: an upstream slave has more children "
         "than open ports (or a module is mounted upside down)";
}

std::string dangling_message(int32_t port) {
  return "port " + std::to_string(port) + " is open but no slave hangs on it (broken link?)";
}

TreeIssue error_at(int32_t position, std::string message) {
  return {TreeIssue::Severity::kError, position, std::move(message)};
}

[[noreturn]] void throw_issue(const TreeIssue& issue) {
  throw DiscoveryError(issue.position, issue.message);
}

}  // namespace

DiscoveryError::DiscoveryError(int32_t position, const std::string& message)
    : std::runtime_error(position > 0 ? "slave " + std::to_string(position) + ": " + message
                                      : message),
      position_(position),
      message_(message) {}

ScanCheck check_scan(const EscScan& scan) {
  using Severity = TreeIssue::Severity;
  ScanCheck out;
  if (scan.slaves.empty()) {
    out.issues.push_back(error_at(0, "the scan has no slaves"));
    return out;
  }
  out.scan = scan;
  auto& sorted = out.scan.slaves;
  std::stable_sort(sorted.begin(), sorted.end(),
                   [](const EscSlave& a, const EscSlave& b) { return a.position < b.position; });
  const auto n = static_cast<int32_t>(sorted.size());
  for (int32_t i = 0; i < n; ++i) {
    const EscSlave& s = sorted[static_cast<std::size_t>(i)];
    std::string problem;
    int32_t at = s.position;
    if (s.position < 1 || s.position > n) {
      problem = "position " + std::to_string(s.position) + " is outside 1.." + std::to_string(n) +
                " (the scan has " + std::to_string(n) + " slaves)";
    } else if (i > 0 && s.position == sorted[static_cast<std::size_t>(i - 1)].position) {
      problem = "position " + std::to_string(s.position) + " appears twice in the scan";
    } else if (s.position != i + 1) {
      at = i + 1;
      problem = "position " + std::to_string(i + 1) + " is missing from the scan (" +
                std::to_string(n) + " slaves)";
    }
    if (!problem.empty()) {
      out.issues.push_back(error_at(at, problem));
      return out;  // positions are the ring order: nothing can be placed
    }
  }
  out.usable = sorted.size();
  for (std::size_t i = 0; i < sorted.size(); ++i) {
    const EscSlave& s = sorted[i];
    if (s.active_ports > 15) {
      out.issues.push_back(error_at(s.position, "active_ports " + std::to_string(s.active_ports) +
                                                    " is not a 4-bit port mask"));
      out.usable = i;
      break;
    }
    if ((s.active_ports & 1U) == 0) {
      out.issues.push_back(error_at(s.position, "port 0 (upstream) is closed in active_ports " +
                                                    mask_text(s.active_ports) +
                                                    ": every slave is reached through port 0 "
                                                    "(module mounted upside down?)"));
      out.usable = i;
      break;
    }
    if (open_count(s) != s.topology) {
      out.issues.push_back({Severity::kWarning, s.position,
                            "topology says " + std::to_string(s.topology) +
                                " open ports but active_ports " + mask_text(s.active_ports) +
                                " has " + std::to_string(open_count(s)) + "; using active_ports"});
    }
  }
  return out;
}

EscScan checked_scan(const EscScan& scan) {
  ScanCheck check = check_scan(scan);
  for (const auto& issue : check.issues) {
    if (issue.severity == TreeIssue::Severity::kError) throw_issue(issue);
  }
  return std::move(check.scan);
}

Network rebuild_network(const EscScan& scan, PortOrder order, std::size_t count) {
  const auto ports_order = frame_order(order);
  Network out;
  out.links.reserve(count);
  // Slaves whose subtree is still open: index and how many of their free ports are used.
  struct Open {
    std::size_t index;
    int32_t used;
    int32_t count;
    std::array<int32_t, 3> ports;
  };
  std::vector<Open> stack;
  stack.reserve(64);
  for (std::size_t i = 0; i < count; ++i) {
    const EscSlave& s = scan.slaves[i];
    SlaveLink link;
    if (i > 0) {
      if (stack.empty()) {
        out.error = error_at(s.position, no_parent_message());
        return out;
      }
      Open& top = stack.back();
      link.parent_position = scan.slaves[top.index].position;
      link.parent_port = top.ports[static_cast<std::size_t>(top.used++)];
      if (top.used == top.count) stack.pop_back();
    }
    out.links.push_back(link);
    Open open{i, 0, 0, {}};
    open.count = downstream_ports(s, ports_order, open.ports);
    if (open.count > 0) stack.push_back(open);
  }
  if (!stack.empty() && count == scan.slaves.size()) {
    const Open& top = stack.back();
    out.error = error_at(scan.slaves[top.index].position,
                         dangling_message(top.ports[static_cast<std::size_t>(top.used)]));
  }
  return out;
}

std::vector<SlaveLink> reconstruct_network(const EscScan& scan, PortOrder order) {
  Network network = rebuild_network(scan, order, scan.slaves.size());
  if (network.error) throw_issue(*network.error);
  return std::move(network.links);
}

// Paper Algorithm 1: walk back from the slave, counting end points (-1), link points (0),
// split points (+1) and cross points (+2) until the counter is non-negative at a slave with
// more than one open port.
namespace {
int32_t find_parent_position(const EscScan& scan, int32_t slave_pos) {
  int32_t parent_pos = 0;
  if (slave_pos > 1) {
    int32_t candidate = slave_pos - 1;
    int32_t topology_counter = 0;
    while (candidate > 0) {
      const int32_t num_open =
          open_count(scan.slaves[static_cast<std::size_t>(candidate - 1)]);
      if (num_open == 1) {
        topology_counter -= 1;
      } else if (num_open == 3) {
        topology_counter += 1;
      } else if (num_open == 4) {
        topology_counter += 2;
      }
      if ((topology_counter >= 0 && num_open > 1) || candidate == 1) {
        parent_pos = candidate;
        candidate = 0;
      }
      candidate -= 1;
    }
  }
  return parent_pos;
}
}  // namespace

// Paper Algorithm 2, with the free-port stack holding only downstream ports (1..3, as its set
// P says) pushed so that the first port in frame order is on top.
std::vector<SlaveLink> reconstruct_network_reference(const EscScan& scan, PortOrder order) {
  const auto ports_order = frame_order(order);
  const auto n = static_cast<int32_t>(scan.slaves.size());
  std::vector<SlaveLink> links(static_cast<std::size_t>(n));
  std::vector<std::vector<int32_t>> free_ports_stack(static_cast<std::size_t>(n));
  for (int32_t i = 1; i <= n; ++i) {
    const auto idx = static_cast<std::size_t>(i - 1);
    const int32_t parent_pos = find_parent_position(scan, i);
    links[idx].parent_position = parent_pos;
    std::array<int32_t, 3> open{};
    int32_t j = downstream_ports(scan.slaves[idx], ports_order, open);
    while (j > 0) {
      free_ports_stack[idx].push_back(open[static_cast<std::size_t>(j - 1)]);
      --j;
    }
    if (parent_pos != 0) {
      auto& parent_stack = free_ports_stack[static_cast<std::size_t>(parent_pos - 1)];
      if (parent_stack.empty()) throw DiscoveryError(i, no_parent_message());
      links[idx].parent_port = parent_stack.back();
      parent_stack.pop_back();
    }
  }
  for (int32_t i = n; i >= 1; --i) {
    const auto& left = free_ports_stack[static_cast<std::size_t>(i - 1)];
    if (!left.empty()) throw DiscoveryError(i, dangling_message(left.back()));
  }
  return links;
}

}  // namespace concert::topology
