// Camera images between two processes on this host, through the project's DDS layer (the
// "localhost" participant: shared memory between local processes): one process publishes
// RGB + depth 640x480 (921,600 + 614,400 bytes) at 15 Hz as the robot's SensorPublisher does
// (convert, write colour, write depth, write camera info), the other receives them.
//  - latency: receive time minus the stamp in the sample (both read CLOCK_REALTIME on one host),
//    for the colour image and for the pair (depth, written second, arrived);
//  - cost on the writer thread: conversion (copy into the IDL sample) and DataWriter::write.
// Writers run in Fast DDS's synchronous publish mode (the catalogue's) and, for comparison, in
// asynchronous mode (a Fast DDS thread sends).
// Usage: bench_sensors_dds [--frames N] [--mode sync|async|both]   (a table and a JSON line per
// mode)
#include <sys/wait.h>
#include <unistd.h>

#include <algorithm>
#include <atomic>
#include <chrono>
#include <iostream>
#include <map>
#include <mutex>
#include <string>
#include <thread>
#include <vector>

#include "concert/cli/cli.hpp"
#include "concert/common/clock.hpp"
#include "concert/dds/endpoint.hpp"
#include "concert/dds/qos.hpp"
#include "concert/idl_schema/cdr.hpp"
#include "concert/sensors_dds/conversions.hpp"
#include "synthetic_sensors.hpp"

namespace concert {
namespace {

using Clock = std::chrono::steady_clock;
using namespace std::chrono_literals;
namespace edds = eprosima::fastdds::dds;

struct Stats {
  double median_us = 0, p99_us = 0, max_us = 0;
  size_t n = 0;
};

Stats stats(std::vector<double> us) {
  Stats s;
  s.n = us.size();
  if (us.empty()) return s;
  std::sort(us.begin(), us.end());
  s.median_us = us[us.size() / 2];
  s.p99_us =
      us[std::min(us.size() - 1, static_cast<size_t>(0.99 * static_cast<double>(us.size())))];
  s.max_us = us.back();
  return s;
}

idl::Json to_json(const Stats& s) {
  return {{"median_us", s.median_us}, {"p99_us", s.p99_us}, {"max_us", s.max_us}, {"n", s.n}};
}

void print(const std::string& what, const Stats& s) {
  std::printf("  %-34s median %9.1f us   p99 %9.1f us   max %9.1f us   (n=%zu)\n", what.c_str(),
              s.median_us, s.p99_us, s.max_us, s.n);
}

/// Receiving side: latencies of the first `frames` pairs, as a JSON line on stdout.
int receiver(int frames, int ready_fd) {
  dds::Participant p({.name = "bench_camera_reader"});
  std::mutex m;
  std::vector<double> rgb_us, pair_us;
  std::atomic<int> pairs{0};
  dds::Reader<msg::Image> rgb(p, dds::topics::camera_rgb, [&](const msg::Image& i, const auto&) {
    const double us = static_cast<double>(now_ns() - i.stamp_ns()) / 1e3;
    std::lock_guard lock(m);
    rgb_us.push_back(us);
  });
  dds::Reader<msg::Image> depth(
      p, dds::topics::camera_depth, [&](const msg::Image& i, const auto&) {
        const double us = static_cast<double>(now_ns() - i.stamp_ns()) / 1e3;
        std::lock_guard lock(m);
        pair_us.push_back(us);
        ++pairs;
      });
  const char ready = 1;
  if (write(ready_fd, &ready, 1) != 1) return 2;
  const auto deadline = Clock::now() + std::chrono::seconds(frames / 15 + 30);
  while (pairs < frames && Clock::now() < deadline) std::this_thread::sleep_for(10ms);
  std::lock_guard lock(m);
  std::cout << idl::Json{{"rgb", to_json(stats(rgb_us))}, {"pair", to_json(stats(pair_us))}}.dump()
            << std::endl;
  return 0;
}

/// A writer on a catalogue topic with the catalogue's QoS in the given publish mode.
edds::DataWriter* make_writer(dds::Participant& p, std::string_view topic, bool async) {
  edds::TypeSupport type(new msg::ImagePubSubType());
  auto qos = dds::writer_qos(dds::find_topic(topic)->qos);
  qos.publish_mode().kind =
      async ? edds::ASYNCHRONOUS_PUBLISH_MODE : edds::SYNCHRONOUS_PUBLISH_MODE;
  auto* w = p.publisher()->create_datawriter(p.topic(std::string(topic), type), qos);
  if (w == nullptr) throw std::runtime_error("cannot create a writer on " + std::string(topic));
  return w;
}

int matched(edds::DataWriter* w) {
  edds::PublicationMatchedStatus s;
  w->get_publication_matched_status(s);
  return s.current_count;
}

int run_mode(bool async, int frames) {
  int pipe_fds[2];
  if (pipe(pipe_fds) != 0) return 2;
  int out_fds[2];
  if (pipe(out_fds) != 0) return 2;
  const pid_t pid = fork();
  if (pid == 0) {
    close(pipe_fds[0]);
    close(out_fds[0]);
    dup2(out_fds[1], STDOUT_FILENO);
    _exit(receiver(frames, pipe_fds[1]));
  }
  close(pipe_fds[1]);
  close(out_fds[1]);
  char ready = 0;
  if (read(pipe_fds[0], &ready, 1) != 1) return 2;

  dds::Participant p({.name = "bench_camera_writer"});
  edds::DataWriter* rgb_w = make_writer(p, dds::topics::camera_rgb.name, async);
  edds::DataWriter* depth_w = make_writer(p, dds::topics::camera_depth.name, async);
  const auto match_deadline = Clock::now() + 20s;
  while ((matched(rgb_w) < 1 || matched(depth_w) < 1) && Clock::now() < match_deadline) {
    std::this_thread::sleep_for(10ms);
  }
  if (matched(rgb_w) < 1 || matched(depth_w) < 1) {
    std::cerr << "bench_sensors_dds: the reader process did not match in 20 s\n";
    kill(pid, SIGKILL);
    return 1;
  }
  std::this_thread::sleep_for(500ms);  // let the reader's side of discovery settle too

  auto frame = testing::synthetic_rgbd_frame("camera_E", 640, 480, 1);
  msg::Image rgb, depth;
  std::vector<double> convert_us, rgb_write_us, depth_write_us;
  const auto period = std::chrono::microseconds(1'000'000 / 15);
  auto next = Clock::now();
  for (int i = 0; i < frames + 5; ++i) {  // a few extra: best-effort may lose some
    next += period;
    std::this_thread::sleep_until(next);
    frame.stamp = static_cast<double>(now_ns()) * 1e-9;
    const auto t0 = Clock::now();
    sensors_dds::to_rgb_image(frame, 1, rgb);
    sensors_dds::to_depth_image(frame, 1, depth);
    rgb.stamp_ns(now_ns());  // the stamp is the write time: latency covers DDS only
    depth.stamp_ns(rgb.stamp_ns());
    const auto t1 = Clock::now();
    rgb_w->write(&rgb);
    const auto t2 = Clock::now();
    depth_w->write(&depth);
    const auto t3 = Clock::now();
    auto us = [](auto d) { return std::chrono::duration<double, std::micro>(d).count(); };
    convert_us.push_back(us(t1 - t0));
    rgb_write_us.push_back(us(t2 - t1));
    depth_write_us.push_back(us(t3 - t2));
  }
  int status = 0;
  waitpid(pid, &status, 0);
  std::string text;
  char buf[4096];
  for (ssize_t n; (n = read(out_fds[0], buf, sizeof buf)) > 0;)
    text.append(buf, static_cast<size_t>(n));
  if (text.empty()) {
    std::cerr << "bench_sensors_dds: no result from the reader process\n";
    return 1;
  }
  const auto r = idl::Json::parse(text);
  const Stats conv = stats(convert_us), rgb_write = stats(rgb_write_us),
              depth_write = stats(depth_write_us);
  std::printf("%s publish mode, 640x480 RGB8 + 16UC1 at 15 Hz, %d frames written:\n",
              async ? "asynchronous" : "synchronous", frames + 5);
  print("latency colour image", {r.at("rgb").at("median_us"), r.at("rgb").at("p99_us"),
                                 r.at("rgb").at("max_us"), r.at("rgb").at("n")});
  print("latency pair (depth arrived)", {r.at("pair").at("median_us"), r.at("pair").at("p99_us"),
                                         r.at("pair").at("max_us"), r.at("pair").at("n")});
  print("writer: convert both (2 copies)", conv);
  print("writer: write() colour 921,600 B", rgb_write);
  print("writer: write() depth 614,400 B", depth_write);
  std::cout << idl::Json{{"mode", async ? "async" : "sync"},   {"frames_written", frames + 5},
                         {"latency_rgb", r.at("rgb")},         {"latency_pair", r.at("pair")},
                         {"convert", to_json(conv)},           {"write_rgb", to_json(rgb_write)},
                         {"write_depth", to_json(depth_write)}}
                   .dump()
            << std::endl;
  p.publisher()->delete_datawriter(rgb_w);
  p.publisher()->delete_datawriter(depth_w);
  return 0;
}

int bench(int frames, const std::string& mode) {
  // Each mode in its own process (this one never starts DDS: forking a process that runs Fast
  // DDS threads is not safe).
  auto in_child = [frames](bool async) {
    std::cout.flush();
    const pid_t pid = fork();
    if (pid == 0) _exit(run_mode(async, frames));
    int status = 0;
    waitpid(pid, &status, 0);
    return WIFEXITED(status) ? WEXITSTATUS(status) : 1;
  };
  int code = 0;
  if (mode == "sync" || mode == "both") code |= in_child(false);
  if (mode == "async" || mode == "both") code |= in_child(true);
  return code;
}

}  // namespace
}  // namespace concert

int main(int argc, char** argv) {
  concert::cli::Cli cli("bench_sensors_dds",
                        "RGB + depth 640x480 at 15 Hz between two processes through the project's "
                        "DDS layer: latency and the writer thread's cost.",
                        std::cout, std::cerr);
  int frames = 300;
  std::string mode = "both";
  auto& app = cli.app();
  app.add_option("--frames", frames, "frame pairs written per mode")
      ->capture_default_str()
      ->check(concert::cli::number(1, 1e6, true));
  concert::cli::Cli::add_choice(app, "--mode", mode, {"sync", "async", "both"},
                                "Fast DDS publish mode(s) to measure")
      ->capture_default_str();
  cli.on_run(app, [&] { return concert::bench(frames, mode); });
  return cli.run(argc, argv);
}
