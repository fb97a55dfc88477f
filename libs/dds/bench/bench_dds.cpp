// DDS benchmark between two processes on loopback, through the project's typed layer:
//  1. small-message round trip: BaseVelocityCommand -> echoed back as Odometry (one-way = RTT/2)
//  2. a 1 kHz JointState stream (18 joints): one-way latency (both processes read the same
//     CLOCK_MONOTONIC) and inter-arrival jitter.
// Usage: bench_dds [--pings N] [--seconds S] [--joints J]   (prints a table and a JSON line)
#include <sys/wait.h>
#include <unistd.h>

#include <algorithm>
#include <atomic>
#include <chrono>
#include <cmath>
#include <cstdio>
#include <cstring>
#include <iostream>
#include <sstream>
#include <string>
#include <thread>
#include <vector>

#include "concert/common/clock.hpp"
#include "concert/dds/endpoint.hpp"

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

/// The echo side of the round trip, and the receiving side of the stream, in a child process.
int child(int pings, int stream_samples) {
  dds::Participant p({.name = "bench_child"});
  dds::Writer<msg::Odometry> pong(p, dds::topics::odometry);
  std::atomic<int> echoed{0};
  dds::Reader<msg::BaseVelocityCommand> ping(p, dds::topics::base_velocity, [&](const msg::BaseVelocityCommand& c, const auto&) {
    msg::Odometry o;
    o.stamp_ns(c.stamp_ns());
    pong.write(o);
    ++echoed;
  });
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
  const auto deadline = Clock::now() + std::chrono::seconds(30 + stream_samples / 1000);
  while (Clock::now() < deadline) {
    {
      std::lock_guard lock(m);
      if (echoed >= pings && static_cast<int>(latency_us.size()) >= stream_samples * 95 / 100 &&
          Clock::now() > deadline - std::chrono::seconds(28)) break;
    }
    std::this_thread::sleep_for(50ms);
  }
  std::lock_guard lock(m);
  if (latency_us.size() < 10) return 1;
  const auto l = stats(latency_us), j = stats(period_us);
  // Report to the parent on stdout (one line).
  std::printf("%zu %f %f %f %f %f %f %f %f\n", latency_us.size(), l.median, l.p99, l.mean, l.max, j.median, j.p99,
              j.mean, j.max);
  std::fflush(stdout);
  return 0;
}

}  // namespace

int bench_main(int argc, char** argv) {
  int pings = 2000, seconds = 5, joints = 18;
  for (int i = 1; i + 1 < argc; i += 2) {
    const std::string a = argv[i];
    if (a == "--pings") pings = std::stoi(argv[i + 1]);
    else if (a == "--seconds") seconds = std::stoi(argv[i + 1]);
    else if (a == "--joints") joints = std::stoi(argv[i + 1]);
    else { std::cerr << "usage: bench_dds [--pings N] [--seconds S] [--joints J]\n"; return 2; }
  }
  const int stream_samples = seconds * 1000;
  int fds[2];
  if (pipe(fds) != 0) return 1;
  const pid_t pid = fork();
  if (pid == 0) {
    dup2(fds[1], 1);
    close(fds[0]);
    _exit(child(pings, stream_samples));
  }
  close(fds[1]);

  dds::Participant p({.name = "bench_parent"});
  dds::Writer<msg::BaseVelocityCommand> ping(p, dds::topics::base_velocity);
  dds::Writer<msg::JointState> stream(p, dds::topics::joint_state);
  std::atomic<int64_t> got_stamp{-1};
  dds::Reader<msg::Odometry> pong(p, dds::topics::odometry, [&](const msg::Odometry& o, const auto&) { got_stamp = o.stamp_ns(); });
  if (!ping.wait_for_readers(1, 20s) || !pong.wait_for_writers(1, 20s) || !stream.wait_for_readers(1, 20s)) {
    std::cerr << "bench_dds: the child process did not match in 20 s\n";
    return 1;
  }
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
  for (int i = 0; i < stream_samples; ++i) {
    next += 1ms;
    std::this_thread::sleep_until(next);
    s.stamp_ns(now_ns());
    stream.write(s);
  }

  char line[512] = {};
  const ssize_t n = read(fds[0], line, sizeof line - 1);
  int status = 0;
  waitpid(pid, &status, 0);
  if (n <= 0 || rtt_us.empty()) {
    std::cerr << "bench_dds: no result from the child process\n";
    return 1;
  }
  size_t received = 0;
  double lm, lp, la, lx, jm, jp, ja, jx;
  std::sscanf(line, "%zu %lf %lf %lf %lf %lf %lf %lf %lf", &received, &lm, &lp, &la, &lx, &jm, &jp, &ja, &jx);
  const auto r = stats(rtt_us);
  std::printf("DDS on loopback, Fast DDS 2.9, two processes (%d pings, %d s stream of %d joints)\n", pings, seconds, joints);
  std::printf("  round trip (command -> state)   median %8.1f us   p99 %8.1f us   (one-way ~ %.1f us)\n", r.median, r.p99, r.median / 2);
  std::printf("  1 kHz JointState latency        median %8.1f us   p99 %8.1f us   max %8.1f us\n", lm, lp, lx);
  std::printf("  1 kHz JointState period         median %8.1f us   p99 %8.1f us   max %8.1f us\n", jm, jp, jx);
  std::printf("  stream samples received         %zu of %d\n", received, stream_samples);
  std::printf("{\"rtt_us\":{\"median\":%.1f,\"p99\":%.1f},\"stream_latency_us\":{\"median\":%.1f,\"p99\":%.1f},"
              "\"stream_period_us\":{\"median\":%.1f,\"p99\":%.1f},\"received\":%zu,\"sent\":%d}\n",
              r.median, r.p99, lm, lp, jm, jp, received, stream_samples);
  return 0;
}

}  // namespace concert

int main(int argc, char** argv) { return concert::bench_main(argc, argv); }
