// DDS benchmark between two processes on loopback, through the project's typed layer:
//  1. small-message round trip: BaseVelocityCommand -> echoed back as Odometry (one-way = RTT/2)
//  2. a 1 kHz JointState stream (18 joints): one-way latency (both processes read the same
//     CLOCK_MONOTONIC) and inter-arrival jitter.
// The commanding side authenticates as "nav" and the robot's side as "robot" when secured: the
// robot's side writes the odometry and the joint state stream, as the robot service does.
// --security runs the same under each DDS Security governance named (a fresh PKI each):
//   off          no security
//   auth         authentication, access control, protected discovery; messages not protected
//   sign         + every RTPS message signed (AES-GMAC): integrity, no confidentiality
//   default      the stack's governance: every RTPS message encrypted (AES-GCM)
//   submessages  each writer's submessages encrypted instead (per-writer keys)
//   encrypt-all  messages, submessages and payloads encrypted (Fast DDS only: see README)
// Usage: bench_dds [--pings N] [--seconds S] [--joints J] [--security off,default,...]
//        (default: off,default; prints a table and a JSON line per mode)
#include <sys/resource.h>
#include <sys/wait.h>
#include <unistd.h>

#include <algorithm>
#include <atomic>
#include <chrono>
#include <cmath>
#include <cstdio>
#include <cstdlib>
#include <cstring>
#include <iostream>
#include <mutex>
#include <optional>
#include <sstream>
#include <string>
#include <thread>
#include <vector>

#include "concert/cli/cli.hpp"
#include "concert/common/clock.hpp"
#include "concert/common/text.hpp"
#include "concert/dds/endpoint.hpp"
#include "concert/security/pki.hpp"
#include "process.hpp"

namespace concert {
using Clock = std::chrono::steady_clock;
using namespace std::chrono_literals;

namespace {

struct Stats {
  double median, p99, mean, max;
};

Stats stats(std::vector<double> v) {
  std::sort(v.begin(), v.end());
  double sum = 0;
  for (double x : v) sum += x;
  auto at = [&](double q) { return v[std::min(v.size() - 1, static_cast<size_t>(q * static_cast<double>(v.size())))]; };
  return {at(0.5), at(0.99), sum / static_cast<double>(v.size()), v.back()};
}

/// CPU time of this process so far [us] (user + system, every thread).
double cpu_us() {
  rusage u{};
  getrusage(RUSAGE_SELF, &u);
  return static_cast<double>(u.ru_utime.tv_sec + u.ru_stime.tv_sec) * 1e6 +
         static_cast<double>(u.ru_utime.tv_usec + u.ru_stime.tv_usec);
}

/// The robot's side in a child process: echoes the round trip and writes the 1 kHz stream;
/// reports the CPU time it spent while streaming on `report` (text, microseconds).
int child(int pings, int stream_samples, int joints, int report) {
  dds::Participant p({.name = "bench_robot", .identity = "robot"});
  dds::Writer<msg::Odometry> pong(p, dds::topics::odometry);
  std::atomic<int> echoed{0};
  dds::Reader<msg::BaseVelocityCommand> ping(p, dds::topics::base_velocity, [&](const msg::BaseVelocityCommand& c, const auto&) {
    msg::Odometry o;
    o.stamp_ns(c.stamp_ns());
    pong.write(o);
    ++echoed;
  });
  dds::Writer<msg::JointState> stream(p, dds::topics::joint_state);
  if (!ping.wait_for_writers(1, 30s) || !stream.wait_for_readers(1, 30s)) return 1;
  const auto deadline = Clock::now() + std::chrono::seconds(60);
  while (echoed < pings && Clock::now() < deadline) std::this_thread::sleep_for(10ms);

  msg::JointState s;
  s.name().resize(static_cast<size_t>(joints));
  for (int j = 0; j < joints; ++j) {
    // Streamed rather than "J" + ...: GCC 12 flags the string concatenation (and assigning "J")
    // with a -Wrestrict false positive when inlined here.
    std::ostringstream name;
    name << "J" << j << "_A";
    s.name()[static_cast<size_t>(j)] = name.str();
  }
  s.position(std::vector<double>(static_cast<size_t>(joints), 0.1));
  s.velocity(std::vector<double>(static_cast<size_t>(joints), 0.2));
  s.effort(std::vector<double>(static_cast<size_t>(joints), 0.3));
  auto next = Clock::now();
  const double cpu0 = cpu_us();
  for (int i = 0; i < stream_samples; ++i) {
    next += 1ms;
    std::this_thread::sleep_until(next);
    s.stamp_ns(now_ns());
    stream.write(s);
  }
  const std::string cpu = std::to_string(cpu_us() - cpu0) + "\n";
  (void)!write(report, cpu.data(), cpu.size());
  // Stay until the parent has read the stream (it closes the pipe).
  char byte = 0;
  (void)!read(0, &byte, 1);
  return 0;
}

struct Result {
  double match_ms;
  Stats rtt, latency, period;
  size_t received;
  double writer_cpu_us, reader_cpu_us;  ///< CPU of each side while the stream ran
};

/// One run: the robot's side forked, this process commands and reads the stream.
std::optional<Result> run(int pings, int stream_samples, int joints) {
  int to_child[2], from_child[2];
  if (pipe(to_child) != 0 || pipe(from_child) != 0) return std::nullopt;
  const auto start = Clock::now();
  const pid_t pid = fork();
  if (pid == 0) {
    dup2(to_child[0], 0);
    close(to_child[1]);
    close(from_child[0]);
    _exit(child(pings, stream_samples, joints, from_child[1]));
  }
  close(to_child[0]);
  close(from_child[1]);

  std::optional<Result> result;
  {
    dds::Participant p({.name = "bench_nav", .identity = "nav"});
    dds::Writer<msg::BaseVelocityCommand> ping(p, dds::topics::base_velocity);
    std::atomic<int64_t> got_stamp{-1};
    dds::Reader<msg::Odometry> pong(p, dds::topics::odometry, [&](const msg::Odometry& o, const auto&) { got_stamp = o.stamp_ns(); });
    std::vector<double> latency_us, period_us;
    latency_us.reserve(static_cast<size_t>(stream_samples));
    int64_t last = 0;
    std::mutex m;
    dds::Reader<msg::JointState> stream(p, dds::topics::joint_state, [&](const msg::JointState& s, const auto&) {
      const int64_t t = now_ns();
      std::lock_guard lock(m);
      latency_us.push_back(static_cast<double>(t - s.stamp_ns()) / 1e3);
      if (last != 0) period_us.push_back(static_cast<double>(t - last) / 1e3);
      last = t;
    });
    if (!ping.wait_for_readers(1, 30s) || !pong.wait_for_writers(1, 30s) || !stream.wait_for_writers(1, 30s)) {
      std::cerr << "bench_dds: the child process did not match in 30 s\n";
    } else {
      const double match_ms = std::chrono::duration<double, std::milli>(Clock::now() - start).count();
      std::this_thread::sleep_for(300ms);
      std::vector<double> rtt_us;
      for (int i = 0; i < pings; ++i) {
        msg::BaseVelocityCommand c;
        const int64_t t0 = now_ns();
        c.stamp_ns(t0);
        ping.write(c);
        const auto deadline = Clock::now() + 1s;
        while (got_stamp.load() != t0 && Clock::now() < deadline) {}
        if (got_stamp.load() == t0) rtt_us.push_back(static_cast<double>(now_ns() - t0) / 1e3);
      }
      // The stream: until 95 % arrived and a second passed since the last sample, at most
      // 10 s after it should have ended.
      const double cpu0 = cpu_us();
      const auto end = Clock::now() + std::chrono::milliseconds(stream_samples) + 10s;
      while (Clock::now() < end) {
        std::this_thread::sleep_for(50ms);
        std::lock_guard lock(m);
        if (static_cast<int>(latency_us.size()) >= stream_samples * 95 / 100 && now_ns() - last > 1'000'000'000) break;
      }
      const double reader_cpu = cpu_us() - cpu0;
      char report[64] = {};
      const ssize_t n = read(from_child[0], report, sizeof report - 1);
      std::lock_guard lock(m);
      if (!rtt_us.empty() && latency_us.size() >= 10 && n > 0) {
        result = Result{match_ms,          stats(rtt_us),         stats(latency_us), stats(period_us),
                        latency_us.size(), std::atof(report), reader_cpu};
      }
    }
  }
  close(to_child[1]);  // the child may go
  close(from_child[0]);
  int status = 0;
  waitpid(pid, &status, 0);
  return result;
}

/// The governance of a --security mode (nullopt: off). Throws for an unknown mode.
std::optional<security::GovernanceOptions> governance(const std::string& mode) {
  using security::Protection;
  const auto only = [](Protection rtps, Protection metadata, Protection data) {
    return security::GovernanceOptions{.rtps = rtps, .metadata = metadata, .data = data};
  };
  if (mode == "off") return std::nullopt;
  if (mode == "default") return security::GovernanceOptions{};
  if (mode == "auth") return only(Protection::kNone, Protection::kNone, Protection::kNone);
  if (mode == "sign") return only(Protection::kSign, Protection::kNone, Protection::kNone);
  if (mode == "submessages") return only(Protection::kNone, Protection::kEncrypt, Protection::kNone);
  if (mode == "encrypt-all") return only(Protection::kEncrypt, Protection::kEncrypt, Protection::kEncrypt);
  throw std::invalid_argument("--security: '" + mode +
                              "' is not off, auth, sign, default, submessages or encrypt-all");
}

}  // namespace

int bench(int pings, int seconds, int joints, const std::string& modes) {
  const int stream_samples = seconds * 1000;
  for (const std::string& mode : split(modes)) {
    const auto options = governance(mode);
    std::optional<testing::TempDir> pki;
    if (options) {
      pki.emplace("concert-bench-pki");
      security::init_pki(pki->path(), {.days = 1, .governance = *options});
      setenv("CONCERT_SECURITY", pki->path().c_str(), 1);
    } else {
      unsetenv("CONCERT_SECURITY");
    }
    const auto r = run(pings, stream_samples, joints);
    if (!r) {
      std::cerr << "bench_dds: no result (security " << mode << ")\n";
      return 1;
    }
    std::printf("DDS on loopback, Fast DDS 2.9, two processes, security %s (%d pings, %d s stream of %d joints)\n",
                mode.c_str(), pings, seconds, joints);
    std::printf("  start -> both sides matched        %8.1f ms\n", r->match_ms);
    std::printf("  round trip (command -> state)   median %8.1f us   p99 %8.1f us   (one-way ~ %.1f us)\n",
                r->rtt.median, r->rtt.p99, r->rtt.median / 2);
    std::printf("  1 kHz JointState latency        median %8.1f us   p99 %8.1f us   max %8.1f us\n",
                r->latency.median, r->latency.p99, r->latency.max);
    std::printf("  1 kHz JointState period         median %8.1f us   p99 %8.1f us   max %8.1f us\n",
                r->period.median, r->period.p99, r->period.max);
    std::printf("  stream samples received         %zu of %d\n", r->received, stream_samples);
    std::printf("  stream CPU, writer / reader     %8.1f / %.1f ms per second of stream\n",
                r->writer_cpu_us / 1e3 / seconds, r->reader_cpu_us / 1e3 / seconds);
    std::printf("{\"security\":\"%s\",\"match_ms\":%.1f,\"rtt_us\":{\"median\":%.1f,\"p99\":%.1f},"
                "\"stream_latency_us\":{\"median\":%.1f,\"p99\":%.1f},"
                "\"stream_period_us\":{\"median\":%.1f,\"p99\":%.1f},\"received\":%zu,\"sent\":%d,"
                "\"stream_cpu_ms_per_s\":{\"writer\":%.1f,\"reader\":%.1f}}\n",
                mode.c_str(), r->match_ms, r->rtt.median, r->rtt.p99, r->latency.median, r->latency.p99,
                r->period.median, r->period.p99, r->received, stream_samples, r->writer_cpu_us / 1e3 / seconds,
                r->reader_cpu_us / 1e3 / seconds);
    std::fflush(stdout);
  }
  return 0;
}

}  // namespace concert

int main(int argc, char** argv) {
  concert::cli::Cli cli("bench_dds",
                        "DDS between two processes on loopback: command -> state round trip and a "
                        "1 kHz JointState stream, under each DDS Security governance named.",
                        std::cout, std::cerr);
  int pings = 2000, seconds = 5, joints = 18;
  std::string modes = "off,default";
  auto& app = cli.app();
  app.add_option("--pings", pings, "round trips measured")
      ->capture_default_str()
      ->check(concert::cli::number(1, 1e9, true));
  app.add_option("--seconds", seconds, "length of the 1 kHz stream [s]")
      ->capture_default_str()
      ->check(concert::cli::number(1, 86400, true));
  app.add_option("--joints", joints, "joints in each JointState sample")
      ->capture_default_str()
      ->check(concert::cli::number(1, 1000, true));
  app.add_option("--security", modes,
                 "governances, comma-separated: off, auth, sign, default, submessages, encrypt-all")
      ->capture_default_str()
      ->type_name("MODE,...")
      ->check(CLI::Validator(
          [](std::string& text) -> std::string {
            try {
              for (const std::string& mode : concert::split(text)) (void)concert::governance(mode);
            } catch (const std::invalid_argument& e) {
              const std::string what = e.what();  // "--security: 'x' is not ...": CLI11 names it
              return what.substr(what.find('\''));
            }
            return "";
          },
          "", "governances"));
  cli.on_run(app, [&] { return concert::bench(pings, seconds, joints, modes); });
  return cli.run(argc, argv);
}
