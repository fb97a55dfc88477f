#pragma once
// Serving a virtual ring on a link (concert_ecat_ring): every frame answered, run-time faults on
// schedule, the assembly re-read on request (a module added or removed while running).

#include <atomic>
#include <functional>
#include <ostream>
#include <stdexcept>
#include <string>
#include <vector>

#include "concert/ethercat/link.hpp"
#include "concert/ethercat/virtual_ring.hpp"

namespace concert::ethercat {

/// A run-time fault (concert_ecat_ring --fault SPEC).
struct RingFault {
  enum class Kind { kPull, kRefuseOp, kLose };
  Kind kind = Kind::kPull;
  std::string module;
  double after_s = 0;      ///< pull: seconds after the first process data frame
  uint16_t code = 0x001A;  ///< refuse-op: the AL status code
  uint64_t one_in = 0;     ///< lose: one frame in this many
  bool done = false;
};

/// A --fault SPEC that cannot be read; what() quotes it and says what is wrong.
class RingFaultError : public std::invalid_argument {
 public:
  using std::invalid_argument::invalid_argument;
};

/// "pull:MODULE@S", "pull:MODULE", "refuse-op:MODULE", "refuse-op:MODULE:0x001B", "lose:N".
/// Throws RingFaultError.
RingFault parse_ring_fault(const std::string& spec);

/// True for a frame whose first datagram is a logical one (LRD, LWR, LRW): process data.
bool is_process_data_frame(std::span<const uint8_t> frame);

class RingServer {
 public:
  /// Applies the faults that hold from the start (refuse-op, lose) and checks that every
  /// module they name is in the assembly (throws simbus::AssemblyError naming it).
  RingServer(VirtualRing& ring, Link& link, std::vector<RingFault> faults, std::ostream& log);

  /// Answers frames until `stop`. When `reload` is set, clears it and re-reads the assembly
  /// with `load` (a failure is logged and the ring stays as it was). Timed faults count from
  /// the first process data frame. Malformed frames are logged (the first five, then every
  /// thousandth).
  void serve(const std::atomic<bool>& stop, std::atomic<bool>& reload,
             const std::function<simbus::Assembly()>& load);

 private:
  VirtualRing& ring_;
  Link& link_;
  std::vector<RingFault> faults_;
  std::ostream& log_;
};

}  // namespace concert::ethercat
