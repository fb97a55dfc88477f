#pragma once
// What an ESC board of a CONCERT module looks like on the bus, stated once. Sources: the paper's
// Appendix A (frame order, port 0 upstream) and a real scan of the CONCERT robot
// (../shared/data/ethercat/concert_robot_18slaves.yaml, see libs/topology/README.md):
//
//  * every ESC forwards a frame through its ports in the same order, port 0 -> EPU -> 3 -> 1
//    -> 2 -> back to 0 (PortOrder::kReal0312; the paper's text simplifies it to 0 -> 1 -> 2 -> 3);
//  * two-port boards (joints, wheels, passive links, end-effectors, base links) use ports 0
//    (input connector) and 1 (output connector): active_ports 0b0011, or 0b0001 at a chain end;
//  * four-port boards (the hub boards: the Mobile Base Hub's power board and hub board, the
//    Torso Hub) take the frame on port 0 and pass it on through ports 3, 1, 2 in that order;
//  * the ESC type register reads 21 on joint and wheel boards, 1280 on passive-link boards, 50
//    on the Mobile Base Hub's power board (its first ESC) and 256 on its hub board.

#include <array>
#include <cstdint>
#include <optional>
#include <string_view>

#include "concert/topology/port_order.hpp"
#include "concert/topology/types.hpp"

namespace concert::topology {

/// Physical ports of an ESC board.
enum class EscBoard {
  kTwoPort,   ///< ports 0 (upstream) and 1
  kFourPort,  ///< ports 0 (upstream), 1, 2, 3
};

/// The board a module of `kind` carries unless its catalogue row says otherwise: four-port
/// for hubs (and unknown modules, which may be anything), two-port for every other kind.
EscBoard default_board(ModuleKind kind);

/// 2 or 4.
int32_t port_count(EscBoard board);

/// True if `port` (0..3) exists on the board.
bool has_port(EscBoard board, int32_t port);

/// Downstream ports of a board in the order the frame meets them; `count` of them are valid:
/// two-port {1}; four-port {3, 1, 2} (real order) or {1, 2, 3} (paper order).
struct DownstreamPorts {
  std::array<int32_t, 3> ports{};
  int32_t count = 0;
};
DownstreamPorts downstream_ports(EscBoard board, PortOrder order);

/// ESC type register value of a board of a module of `kind` when its catalogue row gives
/// none; `secondary`: a further ESC of a multi-ESC module (e.g. the Mobile Base Hub's hub
/// board). Joint, wheel and end-effector boards 21, passive-link and base-link boards 1280,
/// a hub's first ESC 50, further ESCs 256 (end-effector and base-link values are assumed: the
/// real scan has neither).
int32_t default_esc_type(ModuleKind kind, bool secondary);

/// Parses "2" or "4" (an `esc_ports:` catalogue field); empty for anything else.
std::optional<EscBoard> board_from_port_count(int32_t ports);

}  // namespace concert::topology
