#pragma once
// Command line and output shared by the Fast DDS and Cyclone contract peers.
//   peer write|read [--topics all|latched|NAME[,NAME...]] [--seed N] [--timeout-ms T]
//                   [--linger-ms L] [--wait-readers] [--repeat-ms R] [--stale-first]
//                   [--full-images]
// Output: one JSON object per line (event "written", "received", "missing").

#include <algorithm>
#include <chrono>
#include <cstdio>
#include <iostream>
#include <stdexcept>
#include <string>
#include <vector>

#include "concert/cli/cli.hpp"
#include "concert/common/text.hpp"
#include "concert/dds/catalogue.hpp"
#include "concert/idl_schema/cdr.hpp"

namespace concert::contract {

struct PeerArgs {
  bool write = false;
  std::vector<dds::TopicInfo> topics;
  uint32_t seed = 1;
  int timeout_ms = 20000;
  int linger_ms = 0;
  bool wait_readers = false;
  int repeat_ms = 0;         ///< writers: write again every repeat_ms while lingering (0 = once)
  bool stale_first = false;  ///< writers: first write an older sample, then the expected one
  bool full_images = false;  ///< Image samples are full 640x480 frames (see expected_sample)
};

/// Size of the full-size camera images of the contract tests [px].
inline constexpr uint32_t kFullImageWidth = 640;
inline constexpr uint32_t kFullImageHeight = 480;

/// The sample a peer writes on topic `t`: the same on every peer for the same seed. With
/// `full_images`, an Image is a whole 640x480 frame of seeded bytes: RGB8 (921,600 bytes) on
/// the colour topic, 16UC1 (614,400 bytes) on the others.
inline idl::Json expected_sample(const dds::TopicInfo& t, uint32_t seed, bool full_images = false) {
  uint32_t index = 0;
  for (const auto& c : dds::catalogue()) {
    if (c.name == t.name) break;
    ++index;
  }
  idl::Json sample = idl::sample_with_every_field_set(idl::Schema::builtin(), t.type_name, seed * 100 + index);
  if (full_images && t.type_name == "concert::msg::Image") {
    const bool rgb = t.name == "concert/sensors/camera/rgb";
    const uint32_t step = kFullImageWidth * (rgb ? 3 : 2);
    sample["encoding"] = rgb ? "rgb8" : "16UC1";
    sample["width"] = kFullImageWidth;
    sample["height"] = kFullImageHeight;
    sample["step"] = step;
    std::vector<uint8_t> data(static_cast<size_t>(step) * kFullImageHeight);
    uint32_t x = seed * 2654435761u + index;  // xorshift32: the same bytes on every peer
    for (auto& b : data) {
      x ^= x << 13;
      x ^= x >> 17;
      x ^= x << 5;
      b = static_cast<uint8_t>(x);
    }
    sample["data"] = data;
  }
  return sample;
}

/// An older sample of the same instance (same key fields) as expected_sample.
inline idl::Json stale_sample(const dds::TopicInfo& t, uint32_t seed) {
  idl::Json stale = expected_sample(t, seed + 1000);
  const idl::Json expected = expected_sample(t, seed);
  for (const auto& f : idl::Schema::builtin().at(t.type_name).fields) {
    if (f.key) stale[f.name] = expected[f.name];
  }
  return stale;
}

/// The peer's command line. --help exits 0; a wrong command line exits 2 naming the option.
inline PeerArgs parse_peer_args(int argc, char** argv) {
  PeerArgs a;
  std::string mode;
  std::string topics = "all";
  cli::Cli peer(argc > 0 ? argv[0] : "contract_peer",
                "Contract peer: writes or reads every catalogue topic.", std::cout, std::cerr);
  CLI::App& app = peer.app();
  app.add_option("MODE", mode, "write or read")
      ->required()
      ->check(CLI::IsMember({"write", "read"}));
  app.add_option("--topics", topics, "all, latched, or topic names separated by commas")
      ->type_name("T");
  app.add_option("--seed", a.seed, "seed of the expected samples")->type_name("N");
  app.add_option("--timeout-ms", a.timeout_ms, "give up after this long")->type_name("MS");
  app.add_option("--linger-ms", a.linger_ms, "stay this long after the work is done")
      ->type_name("MS");
  app.add_flag("--wait-readers", a.wait_readers, "writers: wait for a matched reader first");
  app.add_option("--repeat-ms", a.repeat_ms, "writers: write again every MS while lingering")
      ->type_name("MS");
  app.add_flag("--stale-first", a.stale_first, "writers: first write an older sample");
  app.add_flag("--full-images", a.full_images, "Image samples are full 640x480 frames");
  bool parsed = false;
  peer.on_run(app, [&parsed] {
    parsed = true;
    return 0;
  });
  const int code = peer.run(argc, argv);
  if (!parsed) std::exit(code);
  a.write = mode == "write";
  // Names compared one by one (no string concatenation: GCC 12 at -O3 flags the inlined
  // operator+ with a -Wrestrict false positive).
  const std::vector<std::string> names = split(topics);
  for (const auto& t : dds::catalogue()) {
    const bool all = topics == "all";
    const bool latched = topics == "latched" && t.qos == dds::QosClass::kLatched;
    const bool named = std::find(names.begin(), names.end(), t.name) != names.end();
    if (all || latched || named) a.topics.push_back(t);
  }
  if (a.topics.empty()) throw std::invalid_argument("no topic matches --topics " + topics);
  return a;
}

inline idl::Json qos_json(bool reliable, bool transient_local, int depth) {
  idl::Json j = {{"reliable", reliable}, {"transient_local", transient_local}};
  if (depth >= 0) j["depth"] = depth;
  return j;
}

inline void emit(const idl::Json& j) {
  std::cout << j.dump() << std::endl;
}

/// Reports the topics that never delivered a sample; returns the peer's exit code.
template <class Endpoints> int report_missing(const Endpoints& endpoints) {
  idl::Json missing = idl::Json::array();
  for (const auto& ep : endpoints) {
    if (!ep.done) missing.push_back(ep.info.name);
  }
  if (missing.empty()) return 0;
  emit({{"event", "missing"}, {"topics", missing}});
  return 1;
}

inline bool past(std::chrono::steady_clock::time_point start, int ms) {
  return std::chrono::steady_clock::now() - start > std::chrono::milliseconds(ms);
}

}  // namespace concert::contract
