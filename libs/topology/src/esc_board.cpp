#include "concert/topology/esc_board.hpp"

namespace concert::topology {

EscBoard default_board(ModuleKind kind) {
  return kind == ModuleKind::kHub || kind == ModuleKind::kUnknown ? EscBoard::kFourPort
                                                                  : EscBoard::kTwoPort;
}

int32_t port_count(EscBoard board) { return board == EscBoard::kTwoPort ? 2 : 4; }

bool has_port(EscBoard board, int32_t port) { return port >= 0 && port < port_count(board); }

DownstreamPorts downstream_ports(EscBoard board, PortOrder order) {
  DownstreamPorts out;
  if (board == EscBoard::kTwoPort) {
    out.ports[0] = 1;
    out.count = 1;
    return out;
  }
  const auto loop = frame_order(order);
  for (std::size_t k = 1; k < 4; ++k) out.ports[k - 1] = loop[k];
  out.count = 3;
  return out;
}

int32_t default_esc_type(ModuleKind kind, bool secondary) {
  switch (kind) {
    case ModuleKind::kJoint:
    case ModuleKind::kWheel:
    case ModuleKind::kEndEffector:
      return 21;
    case ModuleKind::kLink:
    case ModuleKind::kBaseLink:
      return 1280;
    case ModuleKind::kHub:
      return secondary ? 256 : 50;
    case ModuleKind::kUnknown:
      return 0;
  }
  return 0;
}

std::optional<EscBoard> board_from_port_count(int32_t ports) {
  if (ports == 2) return EscBoard::kTwoPort;
  if (ports == 4) return EscBoard::kFourPort;
  return std::nullopt;
}

}  // namespace concert::topology
