#pragma once
// Order in which an ESC forwards an EtherCAT frame through its ports (paper Appendix A).

#include <array>
#include <cstdint>
#include <optional>
#include <string>
#include <string_view>

namespace concert::topology {

/// Frame processing order of a 4-port ESC.
enum class PortOrder {
  kReal0312,     ///< real ESCs: port 0 -> EPU -> 3 -> 1 -> 2 -> back to 0
  kNumeric0123,  ///< the paper's simplified text: 0 -> EPU -> 1 -> 2 -> 3
};

/// The four physical ports in frame order, port 0 first: {0, 3, 1, 2} or {0, 1, 2, 3}.
std::array<int32_t, 4> frame_order(PortOrder order);

/// Parses "0312" or "0123"; empty for anything else.
std::optional<PortOrder> parse_port_order(std::string_view text);

/// "0312" or "0123".
std::string to_string(PortOrder order);

}  // namespace concert::topology
