#include "concert/ethercat/virtual_ring.hpp"

#include <algorithm>
#include <bit>
#include <random>

#include "concert/ethercat/sii.hpp"

namespace concert::ethercat {
namespace {

// Register space and process RAM of an ET1100 (8 KiB of process RAM from 0x1000).
constexpr std::size_t kMemoryBytes = 0x3000;

// Chip types of register 0x0000 (ET1100 and ET1200 datasheets).
constexpr uint8_t kChipEt1100 = 0x11;
constexpr uint8_t kChipEt1200 = 0x12;

/// Registers the EtherCAT side may write (the rest are read-only or PDI-owned, and a write there
/// changes nothing, as on an ESC). Ranges are inclusive.
constexpr std::array<std::pair<uint16_t, uint16_t>, 12> kWritable{{
    {0x0010, 0x0011},  // configured station address
    {0x0100, 0x0103},  // DL control
    {0x0120, 0x0121},  // AL control
    {0x0200, 0x0201},  // ECAT event mask
    {0x0300, 0x0313},  // error counters (a write clears them)
    {0x0400, 0x0401},  // watchdog divider
    {0x0410, 0x0411},  // PDI watchdog time
    {0x0420, 0x0421},  // process data watchdog time
    {0x0500, 0x0500},  // EEPROM configuration (offer to PDI)
    {0x0502, 0x050F},  // EEPROM control, address, data
    {0x0600, 0x09FF},  // FMMUs, sync managers, distributed clocks
    {0x1000, 0x2FFF},  // process RAM
}};

bool writable(std::size_t address) {
  for (const auto& [from, to] : kWritable) {
    if (address >= from && address <= to) return true;
  }
  return false;
}

}  // namespace

VirtualRing::VirtualRing(const simbus::Assembly& assembly, const topology::EscCatalog& catalog,
                         RingParams params, const ProcessDataCatalog* process_data)
    : params_(params), catalog_(catalog), process_data_(process_data), assembly_(assembly) {
  rebuild(assembly_);
}

void VirtualRing::set_dl_status(Esc& e) {
  // DL status: ports with a peer are linked, open and communicating; the others closed. A
  // wrong_topology fault is a physical link without communication (a cable to a module that
  // does not answer) or a link the PHY misses: the linked-port count disagrees with the open
  // ports, as masters that count links then report.
  const simbus::BusEsc& b = e.bus;
  uint16_t dl = esc::kDlPdiOperational;
  uint8_t linked = b.open_ports();
  for (int p = 0; p < 4; ++p) {
    if (linked & (1U << p)) {
      dl |= esc::dl_communication(p);
    } else {
      dl |= esc::dl_loop_closed(p);
    }
  }
  if (b.reported_topology) {
    const int want = *b.reported_topology;
    for (int p = 0; p < 4 && std::popcount(static_cast<unsigned>(linked)) < want; ++p) {
      linked = static_cast<uint8_t>(linked | (1U << p));
    }
    for (int p = 3; p >= 0 && std::popcount(static_cast<unsigned>(linked)) > want; --p) {
      linked = static_cast<uint8_t>(linked & ~(1U << p));
    }
  }
  for (int p = 0; p < 4; ++p) {
    if (linked & (1U << p)) dl |= esc::dl_link(p);
  }
  put16(e, esc::kDlStatus, dl);
}

VirtualRing::Esc VirtualRing::fresh_esc(const simbus::BusEsc& b, std::size_t index) {
  std::mt19937_64 clock(params_.clock_seed * 1'000'003ULL + index);
  Esc e;
  e.bus = b;
  e.memory.assign(kMemoryBytes, 0);
  e.clock_offset_ns = std::uniform_int_distribution<uint64_t>(0, 1'000'000'000ULL)(clock);
  const bool four = b.board == topology::EscBoard::kFourPort;
  e.memory[esc::kType] = four ? kChipEt1100 : kChipEt1200;
  e.memory[esc::kFmmusSupported] = four ? 8 : 3;
  e.memory[esc::kSyncManagersSupported] = four ? 8 : 4;
  e.memory[esc::kRamSize] = four ? 8 : 1;
  e.memory[esc::kPortDescriptor] = four ? 0xAA : 0x0A;  // EBUS on each port the board has
  put16(e, esc::kAlStatus, static_cast<uint16_t>(esc::AlState::kInit));
  if (params_.eeprom_8_byte_reads) put16(e, esc::kEepromControl, esc::kEeprom8ByteRead);
  SiiInfo sii;
  sii.vendor_id = params_.vendor_id;
  sii.product_code = static_cast<uint32_t>(b.esc_type);
  sii.serial = static_cast<uint32_t>(index + 1);
  sii.module = b.identity;
  sii.robot_id = b.robot_id;
  if (process_data_) e.process_data = process_data_->find(b.esc_type);
  if (e.process_data) add_process_data(sii, *e.process_data);
  e.info = sii;
  e.sii = make_sii_image(sii);
  return e;
}

void VirtualRing::rebuild(const simbus::Assembly& as_built) {
  simbus::Assembly assembly = as_built;
  for (const std::string& m : pulled_) {
    assembly.faults.push_back({.type = simbus::FaultType::kBrokenLink, .module = m});
  }
  const simbus::Bus bus = simbus::wire_bus(assembly, catalog_);  // throws before any change
  std::map<std::pair<std::string, int32_t>, Esc> old;
  for (Esc& e : escs_) old.emplace(std::pair{e.bus.module, e.bus.module_esc}, std::move(e));
  escs_.clear();
  for (std::size_t i = 0; i < bus.escs.size(); ++i) {
    const simbus::BusEsc& b = bus.escs[i];
    const auto it = old.find({b.module, b.module_esc});
    if (it != old.end() && it->second.bus.identity == b.identity && it->second.bus.esc_type == b.esc_type) {
      Esc e = std::move(it->second);
      for (int p = 0; p < 4; ++p) {
        // A port that had a peer and has none now: the ESC counts a lost link.
        if (e.bus.peer[static_cast<std::size_t>(p)] != simbus::kNoPeer &&
            b.peer[static_cast<std::size_t>(p)] == simbus::kNoPeer) {
          ++e.memory[esc::kLostLinkCounters + static_cast<std::size_t>(p)];
        }
      }
      e.bus = b;
      escs_.push_back(std::move(e));
    } else {
      escs_.push_back(fresh_esc(b, i));
    }
    Esc& e = escs_.back();
    set_dl_status(e);
    const auto refusing = refusing_.find(b.module);
    e.refuse_op = refusing == refusing_.end() ? 0 : refusing->second;
  }
  path_ = simbus::follow_frame(bus);
  order_.clear();
  step_time_ns_.clear();
  uint64_t t = 0;
  for (const simbus::FrameStep& step : path_) {
    t += step.kind == simbus::FrameStep::Kind::kSend ? params_.cable_delay_ns : params_.esc_delay_ns;
    step_time_ns_.push_back(t);
    if (step.kind == simbus::FrameStep::Kind::kProcess) order_.push_back(step.esc);
  }
}

void VirtualRing::set_assembly(const simbus::Assembly& assembly) {
  // A pulled cable of a module that is no longer there goes with the module.
  std::vector<std::string> pulled = pulled_;
  std::erase_if(pulled, [&](const std::string& m) {
    return std::none_of(assembly.modules.begin(), assembly.modules.end(),
                        [&](const simbus::MountedModule& x) { return x.name == m; });
  });
  std::swap(pulled, pulled_);
  try {
    rebuild(assembly);
  } catch (...) {
    std::swap(pulled, pulled_);
    throw;
  }
  assembly_ = assembly;
}

void VirtualRing::pull_cable(const std::string& module) {
  if (std::find(pulled_.begin(), pulled_.end(), module) != pulled_.end()) return;
  pulled_.push_back(module);
  try {
    rebuild(assembly_);
  } catch (...) {
    pulled_.pop_back();
    throw;
  }
}

void VirtualRing::plug_cable(const std::string& module) {
  std::erase(pulled_, module);
  rebuild(assembly_);
}

void VirtualRing::refuse_op(const std::string& module, uint16_t code) {
  if (std::none_of(assembly_.modules.begin(), assembly_.modules.end(),
                   [&](const simbus::MountedModule& x) { return x.name == module; })) {
    throw simbus::AssemblyError(assembly_.source + ": module '" + module + "' is not in the assembly");
  }
  if (code) {
    refusing_[module] = code;
  } else {
    refusing_.erase(module);
  }
  for (Esc& e : escs_) {
    if (e.bus.module == module) e.refuse_op = code;
  }
}

uint16_t VirtualRing::get16(const Esc& esc, uint16_t at) const {
  return static_cast<uint16_t>(esc.memory[at] | (esc.memory[at + 1u] << 8));
}

void VirtualRing::put16(Esc& esc, uint16_t at, uint16_t value) {
  esc.memory[at] = static_cast<uint8_t>(value & 0xFF);
  esc.memory[at + 1u] = static_cast<uint8_t>(value >> 8);
}

std::span<const uint8_t> VirtualRing::registers(int position) const {
  return escs_.at(static_cast<std::size_t>(order_.at(static_cast<std::size_t>(position - 1)))).memory;
}

void VirtualRing::eeprom_command(Esc& esc) {
  uint16_t control = get16(esc, esc::kEepromControl);
  const uint16_t command = control & esc::kEepromCommandMask;
  control = static_cast<uint16_t>(control & ~(esc::kEepromCommandMask | esc::kEepromErrorMask | esc::kEepromBusy));
  if (params_.eeprom_8_byte_reads) control |= esc::kEeprom8ByteRead;
  if (command == esc::kEepromCommandRead) {
    const uint32_t word = static_cast<uint32_t>(esc.memory[esc::kEepromAddress]) |
                          (static_cast<uint32_t>(esc.memory[esc::kEepromAddress + 1]) << 8) |
                          (static_cast<uint32_t>(esc.memory[esc::kEepromAddress + 2]) << 16) |
                          (static_cast<uint32_t>(esc.memory[esc::kEepromAddress + 3]) << 24);
    const int words = params_.eeprom_8_byte_reads ? 4 : 2;
    for (int k = 0; k < words; ++k) {
      // An erased EEPROM reads 0xFFFF beyond the image.
      const uint16_t value = word + k < esc.sii.size() ? esc.sii[word + k] : 0xFFFF;
      put16(esc, static_cast<uint16_t>(esc::kEepromData + 2 * k), value);
    }
  } else if (command != 0) {
    // Writes and reloads are not offered: the boards' identity is not rewritten from the bus.
    control |= esc::kEepromAcknowledgeError;
  }
  put16(esc, esc::kEepromControl, control);
}

void VirtualRing::al_control(Esc& esc) {
  const uint16_t control = get16(esc, esc::kAlControl);
  const uint16_t status = get16(esc, esc::kAlStatus);
  const auto current = esc::al_state_from(status).value_or(esc::AlState::kInit);
  const auto requested = esc::al_state_from(control);
  const bool error = (status & esc::kAlErrorBit) != 0;
  const bool acknowledge = (control & esc::kAlErrorBit) != 0;
  if (error && !acknowledge && requested != esc::AlState::kInit) return;  // error stays until acknowledged
  const auto set = [&](esc::AlState state, uint16_t code) {
    put16(esc, esc::kAlStatus, static_cast<uint16_t>(static_cast<uint16_t>(state) | (code ? esc::kAlErrorBit : 0)));
    put16(esc, esc::kAlStatusCode, code);
  };
  if (!requested) {
    set(current, 0x0012);  // unknown requested state
    return;
  }
  using S = esc::AlState;
  const S to = *requested;
  const bool allowed = to == S::kInit || to == current ||
                       (current == S::kInit && (to == S::kPreOp || to == S::kBoot)) ||
                       (current == S::kPreOp && to == S::kSafeOp) ||
                       (current == S::kSafeOp && (to == S::kOp || to == S::kPreOp)) ||
                       (current == S::kOp && (to == S::kSafeOp || to == S::kPreOp));
  if (to == S::kBoot) {
    set(current, 0x0013);  // bootstrap not supported
  } else if (!allowed) {
    set(current, 0x0011);  // invalid requested state change
  } else if (to == S::kOp && current != S::kOp && esc.refuse_op) {
    set(current, esc.refuse_op);
  } else if (current == S::kPreOp && to == S::kSafeOp) {
    // An ESC's firmware takes SAFE-OP only with its process data sync managers set as its SII
    // describes them.
    const uint16_t code = check_sync_managers(esc);
    set(code ? current : to, code);
  } else {
    set(to, 0);
  }
}

uint16_t VirtualRing::check_sync_managers(const Esc& esc) const {
  for (const uint8_t type : {SiiSyncManager::kOutputs, SiiSyncManager::kInputs}) {
    const int n = esc.info.sync_manager_of(type);
    if (n < 0) continue;
    const std::size_t bytes = type == SiiSyncManager::kOutputs ? esc.info.output_bytes() : esc.info.input_bytes();
    const auto at = static_cast<uint16_t>(esc::kSyncManager + 8 * n);
    const uint16_t start = get16(esc, at);
    const uint16_t length = get16(esc, static_cast<uint16_t>(at + 2));
    const bool enabled = (esc.memory[at + 6u] & 1) != 0;
    const auto& sm = esc.info.sync_managers[static_cast<std::size_t>(n)];
    if (!enabled || start != sm.start || length != bytes) {
      return type == SiiSyncManager::kOutputs ? 0x001D : 0x001E;  // invalid output / input configuration
    }
  }
  return 0;
}

void VirtualRing::execute_logical(Esc& esc, Datagram& d) {
  // Process data only passes in SAFE-OP (inputs) and OP (both): a board in INIT or PRE-OP
  // neither reads nor writes it and does not count the datagram, which is how the master sees
  // it is not exchanging.
  const auto state = esc::al_state_from(get16(esc, esc::kAlStatus));
  const bool may_write = state == esc::AlState::kOp;
  const bool may_read = may_write || state == esc::AlState::kSafeOp;
  if (!may_read) return;
  const uint32_t first = d.logical_address();
  const uint64_t last = static_cast<uint64_t>(first) + d.data.size();  // exclusive
  // The ESC writes the data as it received it, whatever a read FMMU puts into the frame.
  const std::vector<uint8_t> received = writes(d.command) && may_write ? d.data : std::vector<uint8_t>{};
  bool read = false;
  bool wrote = false;
  const int fmmus = std::min<int>(esc.memory[esc::kFmmusSupported], 16);
  for (int f = 0; f < fmmus; ++f) {
    const auto at = static_cast<std::size_t>(esc::kFmmu + 16 * f);
    if ((esc.memory[at + 12] & 1) == 0) continue;  // not activated
    const uint32_t start = static_cast<uint32_t>(esc.memory[at]) | (static_cast<uint32_t>(esc.memory[at + 1]) << 8) |
                           (static_cast<uint32_t>(esc.memory[at + 2]) << 16) |
                           (static_cast<uint32_t>(esc.memory[at + 3]) << 24);
    const uint16_t length = get16(esc, static_cast<uint16_t>(at + 4));
    const uint16_t physical = get16(esc, static_cast<uint16_t>(at + 8));
    const uint8_t type = esc.memory[at + 11];  // bit 0 read, bit 1 write
    const uint64_t from = std::max<uint64_t>(first, start);
    const uint64_t to = std::min<uint64_t>(last, static_cast<uint64_t>(start) + length);
    if (from >= to) continue;
    for (uint64_t l = from; l < to; ++l) {
      const std::size_t frame_at = static_cast<std::size_t>(l - first);
      const std::size_t memory_at = physical + static_cast<std::size_t>(l - start);
      if (memory_at >= esc.memory.size()) continue;
      if ((type & 1) && reads(d.command)) {
        d.data[frame_at] = esc.memory[memory_at];
        read = true;
      }
      if ((type & 2) && writes(d.command) && may_write) {
        esc.memory[memory_at] = received[frame_at];
        wrote = true;
      }
    }
  }
  if (read || wrote) esc.touched = true;
  d.wkc = static_cast<uint16_t>(d.wkc + (read ? 1 : 0) + (wrote ? 2 : 0));
}

void VirtualRing::after_write(Esc& esc, uint16_t from, uint16_t to) {
  const auto touches = [&](uint16_t a, uint16_t b) { return from <= b && to >= a; };
  if (touches(esc::kAlControl, esc::kAlControl + 1)) al_control(esc);
  if (touches(esc::kEepromControl, esc::kEepromControl + 1)) eeprom_command(esc);
  if (touches(esc::kDcReceiveTimePort0, esc::kDcReceiveTimePort0 + 3)) esc.latch = true;
}

void VirtualRing::execute(Esc& esc, Datagram& d) {
  using C = Command;
  bool addressed = false;
  switch (d.command) {
    case C::kArmw: case C::kFrmw: {
      // Read multiple write (DC time distribution): the addressed slave reads, every other
      // slave writes what the frame carries.
      const bool reader = d.command == C::kArmw ? d.adp == 0 : d.adp == get16(esc, esc::kStationAddress);
      if (d.command == C::kArmw) ++d.adp;
      for (std::size_t k = 0; k < d.data.size(); ++k) {
        const std::size_t a = static_cast<std::size_t>(d.ado) + k;
        if (a >= esc.memory.size()) continue;
        if (reader) {
          d.data[k] = esc.memory[a];
        } else if (writable(a)) {
          esc.memory[a] = d.data[k];
        }
      }
      ++d.wkc;
      return;
    }
    case C::kAprd: case C::kApwr: case C::kAprw:
      addressed = d.adp == 0;
      ++d.adp;  // every ESC counts the position up as the frame passes
      break;
    case C::kFprd: case C::kFpwr: case C::kFprw:
      addressed = d.adp == get16(esc, esc::kStationAddress);
      break;
    case C::kBrd: case C::kBwr: case C::kBrw:
      addressed = true;
      ++d.adp;
      break;
    case C::kLrd: case C::kLwr: case C::kLrw:
      execute_logical(esc, d);
      return;
    default:
      return;  // NOP
  }
  if (!addressed) return;
  const bool broadcast = d.command == C::kBrd || d.command == C::kBrw;
  const std::size_t n = d.data.size();
  // Read-write commands: the frame takes the old contents, the memory the frame's as sent.
  const std::vector<uint8_t> sent = writes(d.command) ? d.data : std::vector<uint8_t>{};
  uint16_t wkc = 0;
  if (reads(d.command)) {
    for (std::size_t k = 0; k < n; ++k) {
      const std::size_t a = static_cast<std::size_t>(d.ado) + k;
      const uint8_t value = a < esc.memory.size() ? esc.memory[a] : 0;
      d.data[k] = broadcast ? static_cast<uint8_t>(d.data[k] | value) : value;
    }
    wkc += 1;
  }
  if (writes(d.command)) {
    for (std::size_t k = 0; k < n; ++k) {
      const std::size_t a = static_cast<std::size_t>(d.ado) + k;
      if (a < esc.memory.size() && writable(a)) esc.memory[a] = sent[k];
    }
    if (n > 0) after_write(esc, d.ado, static_cast<uint16_t>(d.ado + n - 1));
    // ETG.1000.4: a write adds 1, a read-write 3 (1 read + 2 write).
    wkc = static_cast<uint16_t>(wkc + (reads(d.command) ? 2 : 1));
  }
  d.wkc = static_cast<uint16_t>(d.wkc + wkc);
}

std::optional<std::vector<uint8_t>> VirtualRing::process(std::span<const uint8_t> bytes, uint64_t now_ns) {
  if (order_.empty()) return std::nullopt;
  ++seen_;
  if (lose_one_in_ && seen_ % lose_one_in_ == 0) {
    ++counters_.lost;
    return std::nullopt;
  }
  Frame frame;
  try {
    frame = decode(bytes);
  } catch (const FrameError& e) {
    ++counters_.malformed;
    counters_.last_error = e.what();
    return std::nullopt;
  }
  ++counters_.frames;
  counters_.datagrams += frame.datagrams.size();
  for (const int32_t index : order_) {
    Esc& esc = escs_[static_cast<std::size_t>(index)];
    esc.latch = false;
    esc.touched = false;
    for (Datagram& d : frame.datagrams) execute(esc, d);
  }
  // The boards behind the ESCs take their outputs and put their inputs for the next frame.
  if (application_) {
    boards_.clear();
    for (std::size_t position = 0; position < order_.size(); ++position) {
      Esc& esc = escs_[static_cast<std::size_t>(order_[position])];
      if (!esc.process_data || !esc.touched) continue;
      const auto state = esc::al_state_from(get16(esc, esc::kAlStatus));
      if (state != esc::AlState::kOp && state != esc::AlState::kSafeOp) continue;
      BoardIo io;
      io.position = static_cast<int>(position) + 1;
      io.esc = &esc.bus;
      io.board = esc.process_data;
      io.state = *state;
      const int out_sm = esc.info.sync_manager_of(SiiSyncManager::kOutputs);
      const int in_sm = esc.info.sync_manager_of(SiiSyncManager::kInputs);
      if (out_sm >= 0) {
        io.outputs = std::span<const uint8_t>(esc.memory).subspan(
            esc.info.sync_managers[static_cast<std::size_t>(out_sm)].start, esc.info.output_bytes());
      }
      if (in_sm >= 0) {
        io.inputs = std::span<uint8_t>(esc.memory).subspan(
            esc.info.sync_managers[static_cast<std::size_t>(in_sm)].start, esc.info.input_bytes());
      }
      boards_.push_back(io);
    }
    if (!boards_.empty()) application_(boards_, now_ns);
  }
  // DC: the ESCs a write to 0x0900 reached latch the local time the frame's first bit passed
  // each of their ports on its way (ports it did not pass keep their old value).
  for (std::size_t s = 0; s < path_.size(); ++s) {
    const simbus::FrameStep& step = path_[s];
    Esc& esc = escs_[static_cast<std::size_t>(step.esc)];
    if (!esc.latch) continue;
    const uint64_t local = now_ns + step_time_ns_[s] + esc.clock_offset_ns;
    if (step.kind == simbus::FrameStep::Kind::kReceive) {
      const auto at = static_cast<uint16_t>(esc::kDcReceiveTimePort0 + 4 * step.port);
      for (int b = 0; b < 4; ++b) esc.memory[at + b] = static_cast<uint8_t>(local >> (8 * b));
    } else if (step.kind == simbus::FrameStep::Kind::kProcess) {
      for (int b = 0; b < 8; ++b) esc.memory[esc::kDcReceiveTimeEpu + b] = static_cast<uint8_t>(local >> (8 * b));
    }
  }
  // The ESC on the master's port marks the frame as having passed a slave: bit 1 of the source
  // address's first byte (locally administered).
  frame.source[0] = static_cast<uint8_t>(frame.source[0] | 0x02);
  try {
    return encode(frame);
  } catch (const FrameError& e) {
    // Decodable but not sendable (longer than an Ethernet frame): dropped, as the wire would.
    ++counters_.malformed;
    counters_.last_error = e.what();
    return std::nullopt;
  }
}

}  // namespace concert::ethercat
