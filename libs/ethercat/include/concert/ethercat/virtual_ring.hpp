#pragma once
// A virtual EtherCAT ring: the ESCs of an assembly (libs/simbus) answering frames as the real
// ones do. Each ESC has its register space, an SII EEPROM holding its board's identity
// (sii.hpp), its ports wired as the modules are bolted together; a frame runs through the ESCs
// in the real port order (0 -> EPU -> 3 -> 1 -> 2, closed ports looping back), each ESC's EPU
// executing every datagram in turn: auto-increment addresses counted down, station addresses
// matched, broadcast reads OR-ed, working counters incremented, DC receive times latched per
// port. concert_ecat_ring serves one over a network interface; tests call process() directly.

#include <cstdint>
#include <functional>
#include <map>
#include <optional>
#include <span>
#include <string>
#include <vector>

#include "concert/ethercat/esc.hpp"
#include "concert/ethercat/frame.hpp"
#include "concert/ethercat/process_data.hpp"
#include "concert/simbus/assembly.hpp"
#include "concert/simbus/bus.hpp"
#include "concert/topology/esc_catalog.hpp"

namespace concert::ethercat {

/// Tuning of the virtual ring (concert_ecat_ring options).
struct RingParams {
  uint32_t vendor_id = 0;           ///< SII vendor id of every board (the real one is not on record here)
  uint32_t esc_delay_ns = 140;      ///< a frame's time through one ESC step (port to EPU, loopback)
  uint32_t cable_delay_ns = 10;     ///< a frame's time on one cable
  uint64_t clock_seed = 1;          ///< seeds each ESC's local clock offset
  bool eeprom_8_byte_reads = false; ///< ESCs that read 8 bytes per EEPROM command (ET1100 does 4 or 8)
};

/// Counters of what the ring saw.
struct RingCounters {
  uint64_t frames = 0;      ///< EtherCAT frames answered
  uint64_t malformed = 0;   ///< frames dropped as unreadable
  uint64_t datagrams = 0;
  uint64_t lost = 0;        ///< frames lost on purpose (lose_one_in)
  std::string last_error;   ///< why the last malformed frame was dropped
};

/// One board with process data, as a frame left it.
struct BoardIo {
  int position = 0;                        ///< ring position, 1-based
  const simbus::BusEsc* esc = nullptr;     ///< its module, robot_id, identity
  const BoardProcessData* board = nullptr;
  esc::AlState state = esc::AlState::kInit;
  std::span<const uint8_t> outputs;        ///< what the master wrote into sync manager 2
  std::span<uint8_t> inputs;               ///< sync manager 3: read by the next frame
};

/// What runs behind the boards (drives, ...): called after every frame whose logical datagram
/// reached boards in SAFE-OP or OP, with those boards, in ring order.
using RingApplication = std::function<void(std::span<BoardIo> boards, uint64_t now_ns)>;

class VirtualRing {
 public:
  /// The ring of `assembly` (faults applied as simbus applies them); boards whose ESC type has
  /// a row in `process_data` exchange that process data. Throws simbus::AssemblyError.
  VirtualRing(const simbus::Assembly& assembly, const topology::EscCatalog& catalog,
              RingParams params = {}, const ProcessDataCatalog* process_data = nullptr);

  /// Sets what runs behind the boards with process data (none: inputs stay as they are).
  void set_application(RingApplication application) { application_ = std::move(application); }

  /// The robot as assembled now (a module added or removed at run time, a cable pulled or
  /// plugged back): ESCs still there keep their state (station address, AL state, sync
  /// managers, FMMUs, process data); new ones start in INIT without a station address; a port
  /// that loses its peer counts a lost link (0x0310 + port). Throws simbus::AssemblyError and
  /// then keeps the ring as it was.
  void set_assembly(const simbus::Assembly& assembly);
  const simbus::Assembly& assembly() const { return assembly_; }

  /// Run-time faults, as a crew or a worn cable causes them:
  /// the cable from `module` to its parent pulled out (module and subtree gone) or plugged back.
  /// Throws simbus::AssemblyError for a module not in the assembly.
  void pull_cable(const std::string& module);
  void plug_cable(const std::string& module);
  /// The boards of `module` refuse OP (stay in SAFE-OP) with `code` (0: accept OP again).
  void refuse_op(const std::string& module, uint16_t code);
  /// Every `n`-th frame is lost (0: none).
  void lose_one_in(uint64_t n) { lose_one_in_ = n; }

  /// The frame as it comes back to the master after passing every ESC, or nothing when it does
  /// not come back (no ESC on the master's port, or bytes that are not an EtherCAT frame:
  /// counted, the reason in counters().last_error). `now_ns` is the time the frame leaves the
  /// master (the ESCs' clocks run from it).
  std::optional<std::vector<uint8_t>> process(std::span<const uint8_t> frame, uint64_t now_ns);

  /// Number of ESCs answering.
  std::size_t slave_count() const { return order_.size(); }
  const RingCounters& counters() const { return counters_; }

  /// The register bytes of the ESC at ring position `position` (1-based), for tests; valid
  /// until the ring changes (set_assembly, pull_cable, plug_cable).
  std::span<const uint8_t> registers(int position) const;

 private:
  struct Esc {
    simbus::BusEsc bus;
    std::vector<uint8_t> memory;      // registers and process RAM
    std::vector<uint16_t> sii;        // EEPROM words
    uint64_t clock_offset_ns = 0;     // local clock = master time + offset
    bool latch = false;               // a write to 0x0900 in the frame being processed
    bool touched = false;             // a logical datagram reached its process data
    const BoardProcessData* process_data = nullptr;
    SiiInfo info;
    uint16_t refuse_op = 0;           // AL status code for OP requests; 0: OP accepted
  };

  void rebuild(const simbus::Assembly& assembly);
  Esc fresh_esc(const simbus::BusEsc& b, std::size_t index);
  void set_dl_status(Esc& e);
  void execute(Esc& esc, Datagram& d);
  void execute_logical(Esc& esc, Datagram& d);
  uint16_t check_sync_managers(const Esc& esc) const;
  void after_write(Esc& esc, uint16_t from, uint16_t to);
  void eeprom_command(Esc& esc);
  void al_control(Esc& esc);
  uint16_t get16(const Esc& esc, uint16_t at) const;
  void put16(Esc& esc, uint16_t at, uint16_t value);

  RingParams params_;
  topology::EscCatalog catalog_;
  const ProcessDataCatalog* process_data_ = nullptr;
  simbus::Assembly assembly_;             // as assembled, without the pulled cables
  std::vector<std::string> pulled_;       // modules whose cable to the parent is out
  std::map<std::string, uint16_t> refusing_;  // module -> AL status code
  uint64_t lose_one_in_ = 0;
  uint64_t seen_ = 0;
  std::vector<Esc> escs_;                 // bus order
  std::vector<int32_t> order_;            // EPU order: ESC index per ring position
  std::vector<simbus::FrameStep> path_;
  std::vector<uint64_t> step_time_ns_;    // time of each step after the frame leaves the master
  RingCounters counters_;
  RingApplication application_;
  std::vector<BoardIo> boards_;           // scratch for the application, sized once
};

}  // namespace concert::ethercat
