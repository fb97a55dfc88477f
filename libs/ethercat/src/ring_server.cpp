#include "concert/ethercat/ring_server.hpp"

#include <algorithm>
#include <chrono>
#include <cerrno>
#include <cstdlib>
#include <optional>

namespace concert::ethercat {
namespace {

double non_negative(const std::string& spec, const std::string& text, const char* what) {
  char* end = nullptr;
  const double v = std::strtod(text.c_str(), &end);
  if (text.empty() || *end != '\0' || !(v >= 0)) {
    throw RingFaultError("--fault " + spec + ": " + what + " '" + text + "' is not a number >= 0");
  }
  return v;
}

}  // namespace

RingFault parse_ring_fault(const std::string& spec) {
  RingFault f;
  const auto colon = spec.find(':');
  if (colon == std::string::npos) throw RingFaultError("--fault " + spec + ": expected KIND:ARGUMENT");
  const std::string kind = spec.substr(0, colon);
  const std::string arg = spec.substr(colon + 1);
  if (kind == "pull") {
    f.kind = RingFault::Kind::kPull;
    const auto at = arg.find('@');
    f.module = arg.substr(0, at);
    if (at != std::string::npos) f.after_s = non_negative(spec, arg.substr(at + 1), "seconds");
  } else if (kind == "refuse-op") {
    f.kind = RingFault::Kind::kRefuseOp;
    const auto c = arg.find(':');
    f.module = arg.substr(0, c);
    if (c != std::string::npos) {
      const std::string text = arg.substr(c + 1);
      char* end = nullptr;
      const unsigned long code = std::strtoul(text.c_str(), &end, 0);
      if (text.empty() || *end != '\0' || code == 0 || code > 0xFFFF) {
        throw RingFaultError("--fault " + spec + ": AL status code '" + text + "' is not 1..0xFFFF");
      }
      f.code = static_cast<uint16_t>(code);
    }
  } else if (kind == "lose") {
    f.kind = RingFault::Kind::kLose;
    char* end = nullptr;
    errno = 0;
    const unsigned long long n = std::strtoull(arg.c_str(), &end, 10);
    if (arg.empty() || *end != '\0' || errno == ERANGE || arg[0] == '-') {
      throw RingFaultError("--fault " + spec + ": N '" + arg + "' is not a whole number");
    }
    f.one_in = n;
    if (f.one_in < 2) throw RingFaultError("--fault " + spec + ": lose:N needs N >= 2");
  } else {
    throw RingFaultError("--fault " + spec + ": kind '" + kind + "' is not pull, refuse-op or lose");
  }
  if (f.kind != RingFault::Kind::kLose && f.module.empty()) {
    throw RingFaultError("--fault " + spec + ": no module named");
  }
  return f;
}

bool is_process_data_frame(std::span<const uint8_t> frame) {
  const std::size_t at = kEthernetHeaderBytes + kEthercatHeaderBytes;
  if (frame.size() <= at) return false;
  const auto c = static_cast<Command>(frame[at]);
  return c == Command::kLrd || c == Command::kLwr || c == Command::kLrw;
}

RingServer::RingServer(VirtualRing& ring, Link& link, std::vector<RingFault> faults, std::ostream& log)
    : ring_(ring), link_(link), faults_(std::move(faults)), log_(log) {
  const auto& modules = ring_.assembly().modules;
  for (RingFault& f : faults_) {
    if (f.kind == RingFault::Kind::kLose) {
      ring_.lose_one_in(f.one_in);
      continue;
    }
    if (std::none_of(modules.begin(), modules.end(), [&](const simbus::MountedModule& m) { return m.name == f.module; })) {
      throw simbus::AssemblyError("--fault: no module '" + f.module + "' in " + ring_.assembly().source);
    }
    if (f.kind == RingFault::Kind::kRefuseOp) ring_.refuse_op(f.module, f.code);
  }
}

void RingServer::serve(const std::atomic<bool>& stop, std::atomic<bool>& reload,
                       const std::function<simbus::Assembly()>& load) {
  using Clock = std::chrono::steady_clock;
  const auto start = Clock::now();
  std::optional<Clock::time_point> first_process_data;
  uint64_t reported_malformed = 0;
  while (!stop) {
    const auto frame = link_.receive(std::chrono::milliseconds(100));
    if (reload.exchange(false)) {
      try {
        const std::size_t before = ring_.slave_count();
        ring_.set_assembly(load());
        log_ << "concert_ecat_ring: re-read " << ring_.assembly().source << ": " << before << " -> "
             << ring_.slave_count() << " ESCs" << std::endl;
      } catch (const std::exception& e) {
        log_ << "concert_ecat_ring: re-reading the assembly failed, the ring stays as it was: " << e.what() << std::endl;
      }
    }
    if (first_process_data) {
      const double s = std::chrono::duration<double>(Clock::now() - *first_process_data).count();
      for (RingFault& f : faults_) {
        if (f.kind != RingFault::Kind::kPull || f.done || s < f.after_s) continue;
        f.done = true;
        try {
          ring_.pull_cable(f.module);
          log_ << "concert_ecat_ring: pulled the cable of '" << f.module << "' after " << s
               << " s of process data: " << ring_.slave_count() << " ESCs answer" << std::endl;
        } catch (const std::exception& e) {
          // The module went with a re-read assembly: nothing to pull.
          log_ << "concert_ecat_ring: could not pull the cable of '" << f.module << "': " << e.what() << std::endl;
        }
      }
    }
    if (!frame) continue;
    if (!first_process_data && is_process_data_frame(*frame)) first_process_data = Clock::now();
    const auto now = static_cast<uint64_t>(
        std::chrono::duration_cast<std::chrono::nanoseconds>(Clock::now() - start).count());
    if (auto answer = ring_.process(*frame, now)) {
      try {
        link_.send(*answer);
      } catch (const LinkError& e) {
        // The interface went down or is busy: the master sees a lost frame, the ring goes on.
        log_ << "concert_ecat_ring: " << e.what() << std::endl;
      }
    }
    const RingCounters& c = ring_.counters();
    if (c.malformed > reported_malformed) {
      reported_malformed = c.malformed;
      // The first few, then every thousandth: a flood of noise must not flood the log.
      if (reported_malformed <= 5 || reported_malformed % 1000 == 0) {
        log_ << "concert_ecat_ring: dropped frame " << reported_malformed << " that is not EtherCAT: "
             << c.last_error << std::endl;
      }
    }
  }
  const RingCounters& c = ring_.counters();
  log_ << "concert_ecat_ring: stopped after " << c.frames << " frames (" << c.datagrams << " datagrams), "
       << c.malformed << " dropped as malformed, " << c.lost << " lost on purpose" << std::endl;
}

}  // namespace concert::ethercat
