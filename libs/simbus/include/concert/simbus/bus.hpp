#pragma once
// The ESCs of an assembly wired port to port, and the path an EtherCAT frame takes through them.
// simulate_scan reads the scan off this path; the virtual ring (libs/ethercat) runs frames along
// it, datagram by datagram. Rules of the path: libs/simbus/README.md ("How the scan is produced").

#include <array>
#include <cstdint>
#include <optional>
#include <string>
#include <vector>

#include "concert/simbus/assembly.hpp"

namespace concert::simbus {

/// A port's peer when nothing is plugged into it.
inline constexpr int32_t kNoPeer = -1;
/// The peer of the port that faces the EtherCAT master.
inline constexpr int32_t kMasterPeer = -2;

/// One ESC as mounted, faults applied.
struct BusEsc {
  std::string module;        ///< name of the assembly module hosting it
  int32_t module_esc = 0;    ///< 0 = the module's upstream ESC, 1.. further boards
  topology::EscBoard board = topology::EscBoard::kTwoPort;
  topology::EscIdentity identity;
  int32_t esc_type = 0;
  int32_t robot_id = -1;
  /// A wrong_topology fault: the count of ports with a physical link, whatever the links are.
  std::optional<int32_t> reported_topology;
  std::array<int32_t, 4> peer{kNoPeer, kNoPeer, kNoPeer, kNoPeer};  ///< ESC index or kMasterPeer
  std::array<int32_t, 4> peer_port{kNoPeer, kNoPeer, kNoPeer, kNoPeer};

  /// Bit i set = port i has a peer (the open-port mask a master reads).
  uint8_t open_ports() const;
};

/// Every ESC of an assembly. `root` is the ESC on the master, -1 when the master's own link is
/// cut (a broken_link fault on the root module: nothing answers).
struct Bus {
  std::vector<BusEsc> escs;
  int32_t root = -1;
};

/// Wires the assembly's ESCs (inside modules, between modules, the master), faults applied.
/// Throws AssemblyError as validate() does.
Bus wire_bus(const Assembly& assembly, const topology::EscCatalog& catalog,
             topology::PortOrder order = topology::PortOrder::kReal0312);

/// One event on a frame's way through the ring, in the order they happen.
struct FrameStep {
  enum class Kind {
    kReceive,   ///< the frame arrives at `port` of `esc` (from the master or a peer)
    kProcess,   ///< the frame passes the ESC's processing unit (EPU)
    kSend,      ///< the frame leaves through `port` towards its peer (or the master)
    kLoopback,  ///< `port` is closed: the frame loops back inside the ESC
  };
  Kind kind = Kind::kReceive;
  int32_t esc = 0;
  int32_t port = 0;  ///< unused for kProcess
  bool operator==(const FrameStep&) const = default;
};

/// The path of one frame from the master back to it: every receive, EPU pass, send and
/// loopback (ports in `order`, closed ports looping back). Empty when `bus.root` is -1.
std::vector<FrameStep> follow_frame(const Bus& bus,
                                    topology::PortOrder order = topology::PortOrder::kReal0312);

}  // namespace concert::simbus
