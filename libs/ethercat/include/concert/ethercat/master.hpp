#pragma once
// A small user-space EtherCAT master: frames of datagrams over a Link, working counters checked,
// and the bring-up a master does before anything else (ETG.1000.4; SOEM's ecx_config_init does the
// same steps): count the slaves (BRD), reset them to INIT, give each a station address (APWR
// 0x0010), read each one's ESC information, DL status (its ports' link and loop state), DC port
// receive times and SII EEPROM. The result is the scan discovery rebuilds the robot from.
// Written here because Debian 12 packages no EtherCAT master library.

#include <array>
#include <chrono>
#include <cstdint>
#include <stdexcept>
#include <string>
#include <vector>

#include "concert/ethercat/esc.hpp"
#include "concert/ethercat/frame.hpp"
#include "concert/ethercat/link.hpp"
#include "concert/ethercat/sii.hpp"
#include "concert/topology/types.hpp"

namespace concert::ethercat {

/// Tuning of the master (concert scan read takes these as options).
struct MasterParams {
  /// How long to wait for a frame to come back before sending it again.
  std::chrono::microseconds frame_timeout{20000};
  /// How long cycle() waits for its frame: a frame later than this is a lost cycle (one period
  /// at 1 kHz, so a late frame never delays the next cycle).
  std::chrono::microseconds cycle_timeout{1000};
  /// Sends of one frame before the exchange fails (1 = no retry).
  int tries = 3;
  /// Station address of the slave at position 1; the next positions count up from it.
  uint16_t first_station_address = 0x1001;
  /// More slaves than this on one ring is an error (a loop or a fault, not a robot).
  int max_slaves = 256;
  /// EEPROM status reads per EEPROM read before the slave counts as not answering.
  int eeprom_polls = 100;
  /// Words of SII EEPROM read per slave at most (the category list must end before).
  int max_sii_words = 4096;
  /// AL status reads while waiting for a state, and the time between them.
  int state_polls = 200;
  std::chrono::microseconds state_poll_interval{1000};
};

/// A ring that does not answer as an EtherCAT ring must; what() names the slave (position and
/// station address), the command and the register, the working counter got and expected.
class MasterError : public std::runtime_error {
 public:
  using std::runtime_error::runtime_error;
};

/// Everything bring-up read from one slave.
struct SlaveReport {
  int32_t position = 0;           ///< 1..n, ring order (the order the frame meets the EPUs)
  uint16_t station_address = 0;   ///< as assigned
  uint8_t chip_type = 0;          ///< register 0x0000
  uint8_t chip_revision = 0;
  uint16_t chip_build = 0;
  uint8_t fmmus = 0;
  uint8_t sync_managers = 0;
  uint8_t ram_kib = 0;
  uint8_t port_descriptor = 0;    ///< register 0x0007
  uint16_t dl_status = 0;         ///< register 0x0110
  uint16_t al_status = 0;         ///< register 0x0130
  uint16_t al_status_code = 0;    ///< register 0x0134
  /// DC receive times of ports 0..3 (local clock, ns), latched by one broadcast frame.
  std::array<uint32_t, 4> receive_time{};
  SiiInfo sii;
  topology::EscSlave slave;       ///< the scan's row for this slave
};

/// The result of a bring-up.
struct ScanReport {
  std::string link;                  ///< interface name
  std::vector<SlaveReport> slaves;   ///< ring order
  int frames_sent = 0;
  int frames_lost = 0;               ///< frames that did not come back in time (and were resent)

  /// The scan in discovery's format (libs/topology).
  topology::EscScan scan() const;
};

/// Where each slave's process data sits in the master's image: outputs (written by the master)
/// at logical addresses [0, outputs), inputs at [outputs, outputs + inputs), one LRW for all.
struct ProcessImageSlave {
  int32_t position = 0;
  uint16_t station_address = 0;
  std::size_t output_offset = 0;  ///< into ProcessImage::outputs
  std::size_t output_bytes = 0;
  std::size_t input_offset = 0;   ///< into ProcessImage::inputs
  std::size_t input_bytes = 0;
};

struct ProcessImage {
  std::vector<uint8_t> outputs;
  std::vector<uint8_t> inputs;
  std::vector<ProcessImageSlave> slaves;  ///< only slaves with process data, ring order
  /// Working counter of a cycle in which every slave exchanged: 2 per slave with outputs (in
  /// OP), 1 per slave with inputs.
  uint16_t expected_wkc = 0;
  /// The slave at ring position `position`, or nullptr (no process data).
  const ProcessImageSlave* slave(int32_t position) const;
};

/// One cyclic exchange.
struct CycleResult {
  bool returned = false;  ///< the frame came back in time
  uint16_t wkc = 0;
};

/// What the master finds when the ring no longer answers as scanned (a working counter short):
/// which slaves are gone, where a link went down, which slaves flag an AL error.
struct RingDiagnosis {
  int answering = 0;                                  ///< slaves a broadcast read counts now
  std::vector<int32_t> missing;                       ///< scanned positions that do not answer
  std::vector<std::pair<int32_t, int32_t>> links_lost;  ///< (position, port): open at the scan, closed now
  std::vector<std::pair<int32_t, uint16_t>> al_errors;  ///< (position, AL status code)
  /// "slaves 12-15 do not answer (slave 11 lost the link on port 1); slave 3: AL status code
  /// 0x001B (sync manager watchdog)", or "the ring answers as scanned".
  std::string text() const;
  bool healthy() const { return missing.empty() && links_lost.empty() && al_errors.empty(); }
};

class Master {
 public:
  explicit Master(Link& link, MasterParams params = {});

  /// Brings the ring up as far as INIT and reads it. An empty ring (the frame comes back with
  /// working counter 0) is an empty scan. Throws MasterError (nothing comes back, a slave does
  /// not answer, an EEPROM that cannot be read, more than max_slaves) and LinkError.
  ScanReport scan();

  /// Sends `datagrams` in one frame (all with one index) and returns them as they came back.
  /// Resends up to `tries` times. Throws MasterError when nothing comes back, LinkError.
  std::vector<Datagram> exchange(std::vector<Datagram> datagrams);

  /// Sends per-slave datagrams in as few frames as fit, in order; returns the answers in order.
  std::vector<Datagram> exchange_all(std::vector<Datagram> datagrams);

  /// Maps every slave's process data (sizes and sync managers from its SII): writes its sync
  /// managers 2 and 3 and two FMMUs (outputs, inputs), and prepares the cyclic frame. Throws
  /// MasterError (a slave that does not take the configuration, an image larger than one frame).
  ProcessImage map_process_data(const ScanReport& report);

  /// Requests `state` of every slave of the report (acknowledging an AL error a slave shows)
  /// and waits (bounded: `state_polls` reads of the AL status, `state_poll_interval` apart)
  /// until all are in it without an error. Throws MasterError naming each slave that refused,
  /// with its AL status code by name, or that did not get there.
  void request_state(const ScanReport& report, esc::AlState state);

  /// Reads every slave of `report` again (AL status, DL status) and says what changed since.
  /// Never throws for a ring that does not answer: then every slave is missing.
  RingDiagnosis diagnose(const ScanReport& report);

  /// One cycle: sends the outputs and the slaves' inputs space in one LRW, waits for it up to
  /// the cycle timeout (no resend: a late frame is a lost cycle), and copies the inputs back
  /// only when every board exchanged (working counter as expected): otherwise the last inputs
  /// stay. Allocates nothing once the image is mapped (on a RawSocketLink). Throws MasterError
  /// for an image that is not the one mapped, LinkError.
  CycleResult cycle(ProcessImage& image);

  int frames_sent() const { return frames_sent_; }
  int frames_lost() const { return frames_lost_; }

 private:
  Link& link_;
  MasterParams params_;
  Frame frame_;
  std::vector<uint8_t> bytes_;
  uint8_t next_index_ = 0;
  std::vector<uint8_t> cycle_frame_;  // the LRW frame, encoded once by map_process_data
  std::size_t cycle_data_at_ = 0;     // where the datagram's data starts in it
  std::size_t cycle_outputs_ = 0;     // the mapped image's sizes
  std::size_t cycle_inputs_ = 0;
  int frames_sent_ = 0;
  int frames_lost_ = 0;
};

/// A datagram for `command` at station/position `adp`, register `ado`, with `size` zero bytes of
/// data (reads) or `data` (writes).
Datagram make_datagram(Command command, uint16_t adp, uint16_t ado, std::size_t size);
Datagram make_datagram(Command command, uint16_t adp, uint16_t ado, std::vector<uint8_t> data);

/// Little-endian helpers for datagram data.
uint16_t read16(const std::vector<uint8_t>& data, std::size_t at = 0);
uint32_t read32(const std::vector<uint8_t>& data, std::size_t at = 0);
std::vector<uint8_t> bytes16(uint16_t value);

}  // namespace concert::ethercat
