#include "concert/ethercat/master.hpp"

#include <algorithm>
#include <bit>
#include <cstdio>
#include <cstring>
#include <thread>

#include "concert/ethercat/esc.hpp"

namespace concert::ethercat {
namespace {

std::string hex4(uint32_t value) {
  char text[12];
  std::snprintf(text, sizeof text, "0x%04X", value);
  return text;
}

std::string describe(const Datagram& d) {
  return to_string(d.command) + " " + hex4(d.ado);
}

std::string slave_name(const SlaveReport& s) {
  return "slave " + std::to_string(s.position) + " (station " + hex4(s.station_address) + ")";
}

/// Bytes a datagram takes in a frame.
std::size_t wire_size(const Datagram& d) {
  return kDatagramHeaderBytes + d.data.size() + kWorkingCounterBytes;
}

}  // namespace

Datagram make_datagram(Command command, uint16_t adp, uint16_t ado, std::size_t size) {
  Datagram d;
  d.command = command;
  d.adp = adp;
  d.ado = ado;
  d.data.assign(size, 0);
  return d;
}

Datagram make_datagram(Command command, uint16_t adp, uint16_t ado, std::vector<uint8_t> data) {
  Datagram d;
  d.command = command;
  d.adp = adp;
  d.ado = ado;
  d.data = std::move(data);
  return d;
}

uint16_t read16(const std::vector<uint8_t>& data, std::size_t at) {
  return static_cast<uint16_t>(data.at(at) | (data.at(at + 1) << 8));
}

uint32_t read32(const std::vector<uint8_t>& data, std::size_t at) {
  return static_cast<uint32_t>(read16(data, at)) | (static_cast<uint32_t>(read16(data, at + 2)) << 16);
}

std::vector<uint8_t> bytes16(uint16_t value) {
  return {static_cast<uint8_t>(value & 0xFF), static_cast<uint8_t>(value >> 8)};
}

topology::EscScan ScanReport::scan() const {
  topology::EscScan scan;
  for (const SlaveReport& s : slaves) scan.slaves.push_back(s.slave);
  return scan;
}

Master::Master(Link& link, MasterParams params) : link_(link), params_(params), bytes_(kMaxFrameBytes) {
  if (params_.tries < 1) throw MasterError("master: tries must be at least 1");
  if (const auto mac = link_.address()) frame_.source = *mac;
}

std::vector<Datagram> Master::exchange(std::vector<Datagram> datagrams) {
  const uint8_t index = next_index_++;
  for (Datagram& d : datagrams) d.index = index;
  frame_.datagrams = std::move(datagrams);
  const std::size_t size = encode_into(frame_, bytes_);
  for (int attempt = 0; attempt < params_.tries; ++attempt) {
    link_.send(std::span<const uint8_t>(bytes_.data(), size));
    ++frames_sent_;
    const auto deadline = std::chrono::steady_clock::now() + params_.frame_timeout;
    // Past the deadline the link is still polled (without waiting) for what is already queued:
    // a frame that came back while this thread was not running is not lost. Bounded.
    for (int late = 0; late < 64;) {
      auto left = std::chrono::duration_cast<std::chrono::microseconds>(deadline - std::chrono::steady_clock::now());
      if (left.count() <= 0) {
        left = std::chrono::microseconds(0);
        ++late;
      }
      const auto received = link_.receive(left);
      if (!received) break;
      Frame answer;
      try {
        answer = decode(*received);
      } catch (const FrameError&) {
        continue;  // not ours to judge: another frame on the wire
      }
      // Ours: same index, same commands, same sizes (a late answer to an earlier try is fine).
      if (answer.datagrams.size() != frame_.datagrams.size()) continue;
      bool same = true;
      for (std::size_t i = 0; i < answer.datagrams.size() && same; ++i) {
        const Datagram& a = answer.datagrams[i];
        const Datagram& q = frame_.datagrams[i];
        same = a.index == q.index && a.command == q.command && a.ado == q.ado &&
               a.data.size() == q.data.size();
      }
      if (!same) continue;
      return std::move(answer.datagrams);
    }
    ++frames_lost_;
  }
  std::string what = describe(frame_.datagrams.front());
  if (frame_.datagrams.size() > 1) {
    what += " and " + std::to_string(frame_.datagrams.size() - 1) + " more datagram" +
            (frame_.datagrams.size() > 2 ? "s" : "");
  }
  throw MasterError("no EtherCAT frame came back on " + link_.name() + " (" + what + ", " +
                    std::to_string(params_.tries) + " tries of " +
                    std::to_string(params_.frame_timeout.count() / 1000) +
                    " ms): nothing connected, the first module's cable is out or the link is down");
}

std::vector<Datagram> Master::exchange_all(std::vector<Datagram> datagrams) {
  std::vector<Datagram> answers;
  answers.reserve(datagrams.size());
  std::size_t first = 0;
  while (first < datagrams.size()) {
    std::size_t bytes = kEthercatHeaderBytes;
    std::size_t last = first;
    while (last < datagrams.size() && bytes + wire_size(datagrams[last]) <= 1500) {
      bytes += wire_size(datagrams[last]);
      ++last;
    }
    if (last == first) throw MasterError("a datagram of " + std::to_string(datagrams[first].data.size()) +
                                         " bytes does not fit one frame");
    std::vector<Datagram> batch(std::make_move_iterator(datagrams.begin() + static_cast<std::ptrdiff_t>(first)),
                                std::make_move_iterator(datagrams.begin() + static_cast<std::ptrdiff_t>(last)));
    for (Datagram& d : exchange(std::move(batch))) answers.push_back(std::move(d));
    first = last;
  }
  return answers;
}

ScanReport Master::scan() {
  ScanReport report;
  report.link = link_.name();
  const int sent_before = frames_sent_;
  const int lost_before = frames_lost_;

  // 1. Count the slaves: every slave adds 1 to a broadcast read's working counter.
  const std::vector<Datagram> count = exchange({make_datagram(Command::kBrd, 0, esc::kType, 2)});
  const int n = count.front().wkc;
  if (n > params_.max_slaves) {
    throw MasterError(std::to_string(n) + " slaves answer on " + link_.name() + ", more than " +
                      std::to_string(params_.max_slaves) + ": a frame loop or a faulty slave");
  }
  if (n == 0) return report;

  // 2. Every slave to INIT (acknowledging any error), FMMUs and sync managers cleared, the SII
  //    EEPROM given to the EtherCAT side: one frame of broadcast writes.
  const auto reset = exchange({
      make_datagram(Command::kBwr, 0, esc::kAlControl,
                    bytes16(static_cast<uint16_t>(esc::AlState::kInit) | esc::kAlErrorBit)),
      make_datagram(Command::kBwr, 0, esc::kFmmu, std::size_t{16 * 16}),
      make_datagram(Command::kBwr, 0, esc::kSyncManager, std::size_t{8 * 16}),
      make_datagram(Command::kBwr, 0, esc::kEepromConfig, bytes16(0)),
  });
  for (const Datagram& d : reset) {
    if (d.wkc != n) {
      throw MasterError(describe(d) + " reached " + std::to_string(d.wkc) + " of the " +
                        std::to_string(n) + " slaves counted on " + link_.name() +
                        ": the ring changed while being scanned");
    }
  }

  // 3. Station addresses by ring position (auto-increment: the slave whose ADP reaches 0 answers).
  std::vector<Datagram> addresses;
  for (int i = 0; i < n; ++i) {
    addresses.push_back(make_datagram(Command::kApwr, static_cast<uint16_t>(-i), esc::kStationAddress,
                                      bytes16(static_cast<uint16_t>(params_.first_station_address + i))));
  }
  const auto assigned = exchange_all(std::move(addresses));
  report.slaves.resize(static_cast<std::size_t>(n));
  for (int i = 0; i < n; ++i) {
    SlaveReport& s = report.slaves[static_cast<std::size_t>(i)];
    s.position = i + 1;
    s.station_address = static_cast<uint16_t>(params_.first_station_address + i);
    if (assigned[static_cast<std::size_t>(i)].wkc != 1) {
      throw MasterError("slave " + std::to_string(i + 1) + " did not take station address " +
                        hex4(s.station_address) + " (APWR 0x0010, working counter " +
                        std::to_string(assigned[static_cast<std::size_t>(i)].wkc) + ", expected 1)");
    }
  }

  // Per-slave reads of registers, checked for working counter 1.
  const auto read_each = [&](uint16_t ado, std::size_t size) {
    std::vector<Datagram> reads;
    for (const SlaveReport& s : report.slaves) {
      reads.push_back(make_datagram(Command::kFprd, s.station_address, ado, size));
    }
    auto answers = exchange_all(std::move(reads));
    for (std::size_t i = 0; i < answers.size(); ++i) {
      if (answers[i].wkc != 1) {
        throw MasterError(slave_name(report.slaves[i]) + " did not answer " + describe(answers[i]) +
                          " (working counter " + std::to_string(answers[i].wkc) + ", expected 1)");
      }
    }
    return answers;
  };

  // 4. ESC information, DL status, AL status.
  const auto info = read_each(esc::kType, 10);
  const auto dl = read_each(esc::kDlStatus, 2);
  const auto al = read_each(esc::kAlStatus, 6);
  for (std::size_t i = 0; i < report.slaves.size(); ++i) {
    SlaveReport& s = report.slaves[i];
    s.chip_type = info[i].data[0];
    s.chip_revision = info[i].data[1];
    s.chip_build = read16(info[i].data, 2);
    s.fmmus = info[i].data[4];
    s.sync_managers = info[i].data[5];
    s.ram_kib = info[i].data[6];
    s.port_descriptor = info[i].data[7];
    s.dl_status = read16(dl[i].data);
    s.al_status = read16(al[i].data);
    s.al_status_code = read16(al[i].data, 4);
  }

  // 5. DC: one broadcast write to 0x0900 latches every port's receive time as the frame passes.
  exchange({make_datagram(Command::kBwr, 0, esc::kDcReceiveTimePort0, std::size_t{4})});
  const auto times = read_each(esc::kDcReceiveTimePort0, 16);
  for (std::size_t i = 0; i < report.slaves.size(); ++i) {
    for (std::size_t p = 0; p < 4; ++p) report.slaves[i].receive_time[p] = read32(times[i].data, 4 * p);
  }

  // 6. SII EEPROM of every slave, read in parallel: the identity words, then the category list
  //    word by word until each slave's ends.
  std::vector<std::vector<uint16_t>> images(report.slaves.size(),
                                            std::vector<uint16_t>(esc::kSiiFirstCategory, 0));
  const auto eeprom_read = [&](const std::vector<std::size_t>& who, const std::vector<uint32_t>& word) {
    std::vector<Datagram> commands;
    for (std::size_t k = 0; k < who.size(); ++k) {
      std::vector<uint8_t> data = bytes16(esc::kEepromCommandRead);
      for (int b = 0; b < 4; ++b) data.push_back(static_cast<uint8_t>(word[k] >> (8 * b)));
      commands.push_back(make_datagram(Command::kFpwr, report.slaves[who[k]].station_address,
                                       esc::kEepromControl, std::move(data)));
    }
    const auto written = exchange_all(std::move(commands));
    for (std::size_t k = 0; k < who.size(); ++k) {
      if (written[k].wkc != 1) {
        throw MasterError(slave_name(report.slaves[who[k]]) + " did not take the EEPROM read " +
                          "command for word " + hex4(word[k]) + " (FPWR 0x0502, working counter " +
                          std::to_string(written[k].wkc) + ")");
      }
    }
    std::vector<uint16_t> status(who.size(), esc::kEepromBusy);
    for (int poll = 0; poll < params_.eeprom_polls; ++poll) {
      std::vector<Datagram> reads;
      std::vector<std::size_t> busy;
      for (std::size_t k = 0; k < who.size(); ++k) {
        if ((status[k] & esc::kEepromBusy) == 0) continue;
        busy.push_back(k);
        reads.push_back(make_datagram(Command::kFprd, report.slaves[who[k]].station_address,
                                      esc::kEepromControl, 2));
      }
      if (busy.empty()) break;
      const auto answers = exchange_all(std::move(reads));
      for (std::size_t j = 0; j < busy.size(); ++j) {
        if (answers[j].wkc == 1) status[busy[j]] = read16(answers[j].data);
      }
    }
    std::vector<Datagram> data_reads;
    for (std::size_t k = 0; k < who.size(); ++k) {
      const SlaveReport& s = report.slaves[who[k]];
      if (status[k] & esc::kEepromBusy) {
        throw MasterError(slave_name(s) + ": EEPROM still busy after " +
                          std::to_string(params_.eeprom_polls) + " status reads (word " +
                          hex4(word[k]) + ")");
      }
      if (status[k] & esc::kEepromErrorMask) {
        throw MasterError(slave_name(s) + ": EEPROM read of word " + hex4(word[k]) +
                          " failed (status " + hex4(status[k]) + ")");
      }
      const std::size_t size = (status[k] & esc::kEeprom8ByteRead) ? 8 : 4;
      data_reads.push_back(make_datagram(Command::kFprd, s.station_address, esc::kEepromData, size));
    }
    auto data = exchange_all(std::move(data_reads));
    for (std::size_t k = 0; k < who.size(); ++k) {
      if (data[k].wkc != 1) {
        throw MasterError(slave_name(report.slaves[who[k]]) + " did not answer FPRD 0x0508 " +
                          "(EEPROM data of word " + hex4(word[k]) + ")");
      }
    }
    return data;
  };
  const auto store = [&](std::size_t slave, uint32_t word, const Datagram& d) {
    std::vector<uint16_t>& image = images[slave];
    for (std::size_t b = 0; b + 1 < d.data.size(); b += 2) {
      const std::size_t at = word + b / 2;
      if (at >= image.size()) image.resize(at + 1, 0);
      image[at] = read16(d.data, b);
    }
  };
  std::vector<std::size_t> everyone(report.slaves.size());
  for (std::size_t i = 0; i < everyone.size(); ++i) everyone[i] = i;
  for (uint32_t word = esc::kSiiVendorId; word < esc::kSiiSerial + 2;) {
    const auto data = eeprom_read(everyone, std::vector<uint32_t>(everyone.size(), word));
    std::size_t got = data.front().data.size() / 2;
    for (std::size_t i = 0; i < everyone.size(); ++i) {
      store(i, word, data[i]);
      got = std::min(got, data[i].data.size() / 2);
    }
    word += static_cast<uint32_t>(got);
  }
  // The category list, from word 0x0040 on, until each image is complete.
  std::vector<uint32_t> next(report.slaves.size(), esc::kSiiFirstCategory);
  while (true) {
    std::vector<std::size_t> who;
    std::vector<uint32_t> words;
    for (std::size_t i = 0; i < report.slaves.size(); ++i) {
      images[i].resize(std::max<std::size_t>(images[i].size(), next[i]));
      if (sii_image_complete(std::span<const uint16_t>(images[i].data(), next[i]))) continue;
      if (next[i] >= static_cast<uint32_t>(params_.max_sii_words)) {
        throw MasterError(slave_name(report.slaves[i]) + ": SII category list has no end within " +
                          std::to_string(params_.max_sii_words) + " words");
      }
      who.push_back(i);
      words.push_back(next[i]);
    }
    if (who.empty()) break;
    const auto data = eeprom_read(who, words);
    for (std::size_t k = 0; k < who.size(); ++k) {
      store(who[k], words[k], data[k]);
      next[who[k]] += static_cast<uint32_t>(data[k].data.size() / 2);
    }
  }

  // 7. The scan's rows.
  for (std::size_t i = 0; i < report.slaves.size(); ++i) {
    SlaveReport& s = report.slaves[i];
    try {
      s.sii = parse_sii_image(std::span<const uint16_t>(images[i].data(), next[i]));
    } catch (const SiiError& e) {
      throw MasterError(slave_name(s) + ": " + e.what());
    }
    s.slave.position = s.position;
    s.slave.active_ports = esc::open_ports(s.dl_status);
    s.slave.topology = std::popcount(static_cast<unsigned>(esc::linked_ports(s.dl_status)));
    s.slave.esc_type = static_cast<int32_t>(s.sii.product_code);
    s.slave.identity = s.sii.module.value_or(topology::EscIdentity{});
    s.slave.robot_id = s.sii.module ? s.sii.robot_id : -1;
  }
  report.frames_sent = frames_sent_ - sent_before;
  report.frames_lost = frames_lost_ - lost_before;
  return report;
}

const ProcessImageSlave* ProcessImage::slave(int32_t position) const {
  for (const ProcessImageSlave& s : slaves) {
    if (s.position == position) return &s;
  }
  return nullptr;
}

ProcessImage Master::map_process_data(const ScanReport& report) {
  ProcessImage image;
  std::size_t outputs = 0;
  std::size_t inputs = 0;
  for (const SlaveReport& s : report.slaves) {
    const int out_sm = s.sii.sync_manager_of(SiiSyncManager::kOutputs);
    const int in_sm = s.sii.sync_manager_of(SiiSyncManager::kInputs);
    const std::size_t out = out_sm >= 0 ? s.sii.output_bytes() : 0;
    const std::size_t in = in_sm >= 0 ? s.sii.input_bytes() : 0;
    if (out == 0 && in == 0) continue;
    // What the SII says must fit the ESC: sync managers it has, two FMMUs.
    const int sms = std::min<int>(s.sync_managers ? s.sync_managers : 16, 16);
    if (std::max(out_sm, in_sm) >= sms) {
      throw MasterError(slave_name(s) + ": its SII puts process data in sync manager " +
                        std::to_string(std::max(out_sm, in_sm)) + ", the ESC has " + std::to_string(sms));
    }
    if (s.fmmus < 2) {
      throw MasterError(slave_name(s) + ": process data needs 2 FMMUs, the ESC has " + std::to_string(s.fmmus));
    }
    image.slaves.push_back({s.position, s.station_address, outputs, out, inputs, in});
    outputs += out;
    inputs += in;
    image.expected_wkc = static_cast<uint16_t>(image.expected_wkc + (out ? 2 : 0) + (in ? 1 : 0));
  }
  if (outputs + inputs > kMaxDatagramData) {
    throw MasterError("process data of " + std::to_string(outputs + inputs) + " bytes does not fit one " +
                      "frame (" + std::to_string(kMaxDatagramData) + ")");
  }
  image.outputs.assign(outputs, 0);
  image.inputs.assign(inputs, 0);
  // Sync managers 2 and 3 as the SII describes them, FMMU 0 (outputs, write) and 1 (inputs,
  // read) onto them: one frame per kind of register, every slave in it.
  std::vector<Datagram> config;
  for (const ProcessImageSlave& m : image.slaves) {
    const SlaveReport& s = report.slaves.at(static_cast<std::size_t>(m.position - 1));
    const auto sm = [&](uint8_t type, std::size_t bytes) {
      const int n = s.sii.sync_manager_of(type);
      const SiiSyncManager& d = s.sii.sync_managers[static_cast<std::size_t>(n)];
      std::vector<uint8_t> r(8, 0);
      r[0] = static_cast<uint8_t>(d.start & 0xFF);
      r[1] = static_cast<uint8_t>(d.start >> 8);
      r[2] = static_cast<uint8_t>(bytes & 0xFF);
      r[3] = static_cast<uint8_t>(bytes >> 8);
      r[4] = d.control;
      r[6] = 1;  // activate
      config.push_back(make_datagram(Command::kFpwr, s.station_address,
                                     static_cast<uint16_t>(esc::kSyncManager + 8 * n), std::move(r)));
      return d.start;
    };
    const auto fmmu = [&](int n, uint32_t logical, std::size_t bytes, uint16_t physical, uint8_t type) {
      std::vector<uint8_t> r(16, 0);
      for (int b = 0; b < 4; ++b) r[static_cast<std::size_t>(b)] = static_cast<uint8_t>(logical >> (8 * b));
      r[4] = static_cast<uint8_t>(bytes & 0xFF);
      r[5] = static_cast<uint8_t>(bytes >> 8);
      r[6] = 0;  // logical start bit
      r[7] = 7;  // logical stop bit
      r[8] = static_cast<uint8_t>(physical & 0xFF);
      r[9] = static_cast<uint8_t>(physical >> 8);
      r[10] = 0;
      r[11] = type;
      r[12] = 1;  // activate
      config.push_back(make_datagram(Command::kFpwr, s.station_address,
                                     static_cast<uint16_t>(esc::kFmmu + 16 * n), std::move(r)));
    };
    if (m.output_bytes) {
      const uint16_t at = sm(SiiSyncManager::kOutputs, m.output_bytes);
      fmmu(0, static_cast<uint32_t>(m.output_offset), m.output_bytes, at, 2);
    }
    if (m.input_bytes) {
      const uint16_t at = sm(SiiSyncManager::kInputs, m.input_bytes);
      fmmu(1, static_cast<uint32_t>(outputs + m.input_offset), m.input_bytes, at, 1);
    }
  }
  const auto answers = exchange_all(std::move(config));
  for (const Datagram& d : answers) {
    if (d.wkc != 1) {
      throw MasterError("station " + hex4(d.adp) + " did not take its process data configuration (" +
                        describe(d) + ", working counter " + std::to_string(d.wkc) + ")");
    }
  }
  // The cyclic frame, encoded once: an LRW over [0, outputs + inputs).
  Frame f;
  f.source = frame_.source;
  Datagram lrw = make_datagram(Command::kLrw, 0, 0, outputs + inputs);
  lrw.set_logical_address(0);
  f.datagrams = {lrw};
  cycle_frame_ = encode(f);
  cycle_data_at_ = kEthernetHeaderBytes + kEthercatHeaderBytes + kDatagramHeaderBytes;
  cycle_outputs_ = outputs;
  cycle_inputs_ = inputs;
  return image;
}

void Master::request_state(const ScanReport& report, esc::AlState state) {
  // A slave showing an AL error takes no request until the error is acknowledged: read first,
  // and acknowledge where an error shows.
  std::vector<Datagram> before;
  for (const SlaveReport& s : report.slaves) {
    before.push_back(make_datagram(Command::kFprd, s.station_address, esc::kAlStatus, 2));
  }
  const auto shown = exchange_all(std::move(before));
  std::vector<Datagram> requests;
  for (std::size_t i = 0; i < report.slaves.size(); ++i) {
    const bool error = shown[i].wkc == 1 && (read16(shown[i].data) & esc::kAlErrorBit);
    requests.push_back(make_datagram(Command::kFpwr, report.slaves[i].station_address, esc::kAlControl,
                                     bytes16(static_cast<uint16_t>(static_cast<uint16_t>(state) |
                                                                   (error ? esc::kAlErrorBit : 0)))));
  }
  exchange_all(std::move(requests));
  std::vector<uint16_t> status(report.slaves.size(), 0);
  std::vector<uint16_t> code(report.slaves.size(), 0);
  for (int poll = 0; poll < params_.state_polls; ++poll) {
    std::vector<Datagram> reads;
    for (const SlaveReport& s : report.slaves) {
      reads.push_back(make_datagram(Command::kFprd, s.station_address, esc::kAlStatus, 6));
    }
    const auto answers = exchange_all(std::move(reads));
    bool all = true;
    bool refused = false;
    for (std::size_t i = 0; i < answers.size(); ++i) {
      if (answers[i].wkc != 1) {
        all = false;
        continue;
      }
      status[i] = read16(answers[i].data);
      code[i] = read16(answers[i].data, 4);
      if (status[i] & esc::kAlErrorBit) {
        refused = true;
        all = false;
      }
      if ((status[i] & esc::kAlStateMask) != static_cast<uint16_t>(state)) all = false;
    }
    if (all) return;
    if (refused) break;
    std::this_thread::sleep_for(params_.state_poll_interval);
  }
  std::string why;
  for (std::size_t i = 0; i < report.slaves.size(); ++i) {
    if ((status[i] & esc::kAlStateMask) == static_cast<uint16_t>(state) && !(status[i] & esc::kAlErrorBit)) continue;
    if (!why.empty()) why += "; ";
    const auto now = esc::al_state_from(status[i]);
    why += slave_name(report.slaves[i]) + " is in " + (now ? esc::to_string(*now) : hex4(status[i]));
    if (status[i] & esc::kAlErrorBit) {
      why += ", AL status code " + hex4(code[i]) + " (" + esc::al_status_code_name(code[i]) + ")";
    }
  }
  throw MasterError("the ring did not reach " + esc::to_string(state) + ": " + why);
}

CycleResult Master::cycle(ProcessImage& image) {
  CycleResult result;
  if (cycle_frame_.empty()) throw MasterError("cycle() before map_process_data()");
  if (image.outputs.size() != cycle_outputs_ || image.inputs.size() != cycle_inputs_) {
    throw MasterError("cycle() with an image of " + std::to_string(image.outputs.size()) + " + " +
                      std::to_string(image.inputs.size()) + " bytes; the one mapped has " +
                      std::to_string(cycle_outputs_) + " + " + std::to_string(cycle_inputs_));
  }
  const uint8_t index = next_index_++;
  uint8_t* frame = cycle_frame_.data();
  const std::size_t head = kEthernetHeaderBytes + kEthercatHeaderBytes;
  frame[head + 1] = index;
  std::memcpy(frame + cycle_data_at_, image.outputs.data(), image.outputs.size());
  const std::size_t wkc_at = cycle_data_at_ + image.outputs.size() + image.inputs.size();
  frame[wkc_at] = 0;
  frame[wkc_at + 1] = 0;
  link_.send(cycle_frame_);
  ++frames_sent_;
  const auto deadline = std::chrono::steady_clock::now() + params_.cycle_timeout;
  for (int late = 0; late < 64;) {
    auto left = std::chrono::duration_cast<std::chrono::microseconds>(deadline - std::chrono::steady_clock::now());
    if (left.count() <= 0) {
      left = std::chrono::microseconds(0);  // what is already queued still counts
      ++late;
    }
    const auto received = link_.receive(left);
    if (!received) break;
    const std::span<const uint8_t> r = *received;
    // Ours: the same LRW (command, index) of the same length; anything else is not this cycle's.
    if (r.size() < wkc_at + 2 || r[12] != 0x88 || r[13] != 0xA4) continue;
    if (r[head] != static_cast<uint8_t>(Command::kLrw) || r[head + 1] != index) continue;
    result.returned = true;
    result.wkc = static_cast<uint16_t>(r[wkc_at] | (r[wkc_at + 1] << 8));
    // A board that did not exchange left the zeros the frame carried: keep the last inputs.
    if (result.wkc == image.expected_wkc) {
      std::memcpy(image.inputs.data(), r.data() + cycle_data_at_ + image.outputs.size(), image.inputs.size());
    }
    return result;
  }
  ++frames_lost_;
  return result;
}

std::string RingDiagnosis::text() const {
  if (healthy()) return "the ring answers as scanned";
  std::string t;
  // Runs of consecutive positions: "slaves 12-15", "slave 3".
  for (std::size_t i = 0; i < missing.size();) {
    std::size_t j = i;
    while (j + 1 < missing.size() && missing[j + 1] == missing[j] + 1) ++j;
    if (!t.empty()) t += ", ";
    t += i == j ? "slave " + std::to_string(missing[i])
                : "slaves " + std::to_string(missing[i]) + "-" + std::to_string(missing[j]);
    i = j + 1;
  }
  if (!missing.empty()) t += missing.size() == 1 ? " does not answer" : " do not answer";
  std::string links;
  for (const auto& [position, port] : links_lost) {
    if (!links.empty()) links += ", ";
    links += "slave " + std::to_string(position) + " lost the link on port " + std::to_string(port);
  }
  if (!links.empty()) t += t.empty() ? links : " (" + links + ")";
  for (const auto& [position, code] : al_errors) {
    if (!t.empty()) t += "; ";
    t += "slave " + std::to_string(position) + ": AL status code " + hex4(code) + " (" +
         esc::al_status_code_name(code) + ")";
  }
  return t;
}

RingDiagnosis Master::diagnose(const ScanReport& report) {
  RingDiagnosis d;
  try {
    d.answering = exchange({make_datagram(Command::kBrd, 0, esc::kType, 2)}).front().wkc;
    std::vector<Datagram> reads;
    for (const SlaveReport& s : report.slaves) {
      reads.push_back(make_datagram(Command::kFprd, s.station_address, esc::kDlStatus, 2));
      reads.push_back(make_datagram(Command::kFprd, s.station_address, esc::kAlStatus, 6));
    }
    const auto answers = exchange_all(std::move(reads));
    for (std::size_t i = 0; i < report.slaves.size(); ++i) {
      const SlaveReport& s = report.slaves[i];
      const Datagram& dl = answers[2 * i];
      const Datagram& al = answers[2 * i + 1];
      if (dl.wkc != 1 || al.wkc != 1) {
        d.missing.push_back(s.position);
        continue;
      }
      const uint8_t was = esc::open_ports(s.dl_status);
      const uint8_t now = esc::open_ports(read16(dl.data));
      for (int p = 0; p < 4; ++p) {
        if ((was & (1U << p)) && !(now & (1U << p))) d.links_lost.emplace_back(s.position, p);
      }
      if (read16(al.data) & esc::kAlErrorBit) d.al_errors.emplace_back(s.position, read16(al.data, 4));
    }
  } catch (const MasterError&) {
    d.answering = 0;
    d.missing.clear();
    for (const SlaveReport& s : report.slaves) d.missing.push_back(s.position);
  }
  return d;
}

}  // namespace concert::ethercat
