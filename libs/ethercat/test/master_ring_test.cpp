// The master against the virtual ring in-process: every example assembly of libs/simbus and
// seeded random robots give, frame by frame, the scan the simulated bus computes.

#include <gtest/gtest.h>

#include <random>

#include "concert/ethercat/esc.hpp"
#include "concert/ethercat/master.hpp"
#include "concert/ethercat/virtual_ring.hpp"
#include "concert/simbus/random_robot.hpp"
#include "concert/topology/scan_io.hpp"
#include "test_data.hpp"

namespace concert::ethercat {
namespace {

using simbus::Assembly;
using topology::EscCatalog;

struct Bench {
  VirtualRing ring;
  uint64_t now = 0;
  int drop_first = 0;  // frames to lose before answering
  LoopbackLink link{[this](std::span<const uint8_t> frame) -> std::optional<std::vector<uint8_t>> {
    now += 100'000;
    if (drop_first > 0) {
      --drop_first;
      return std::nullopt;
    }
    return ring.process(frame, now);
  }};
  Bench(const Assembly& a, const EscCatalog& c, RingParams p = {}) : ring(a, c, p) {}
};

MasterParams quick() {
  MasterParams p;
  p.frame_timeout = std::chrono::microseconds(1000);
  return p;
}

TEST(MasterRing, ScansEveryExampleAsTheSimulatedBus) {
  const EscCatalog catalog = EscCatalog::load(test_data::kPublicDb);
  for (const char* file : {"concert_paper_robot.yaml", "concert_robot_18slaves.yaml",
                           "concert_torso_two_arms.yaml", "faulty_upside_down_elbow.yaml"}) {
    SCOPED_TRACE(file);
    const Assembly a = simbus::load_assembly(test_data::kExamples + "/" + file);
    Bench bench(a, catalog);
    Master master(bench.link, quick());
    const ScanReport report = master.scan();
    EXPECT_EQ(report.scan(), simbus::simulate_scan(a, catalog));
    EXPECT_EQ(report.frames_lost, 0);
    ASSERT_FALSE(report.slaves.empty());
    // DC: the port a slave's frame came in by latched the earliest receive time of its open
    // ports; that is port 0, but on the elbow mounted upside down (entered through port 1).
    int entered_elsewhere = 0;
    for (const SlaveReport& s : report.slaves) {
      EXPECT_EQ(s.station_address, 0x1000 + s.position);
      EXPECT_EQ(esc::al_state_from(s.al_status), esc::AlState::kInit);
      int first = -1;
      for (int p = 0; p < 4; ++p) {
        if ((s.slave.active_ports & (1U << p)) == 0) continue;
        if (first < 0 || s.receive_time[static_cast<std::size_t>(p)] <
                             s.receive_time[static_cast<std::size_t>(first)]) {
          first = p;
        }
      }
      if (first != 0) ++entered_elsewhere;
    }
    EXPECT_EQ(entered_elsewhere, std::string(file).starts_with("faulty_upside_down") ? 1 : 0);
  }
}

TEST(MasterRing, TheRealRobotsEighteenModulesGiveTheRealScan) {
  const EscCatalog catalog = EscCatalog::load(test_data::kPublicDb);
  const Assembly a = simbus::load_assembly(test_data::kExamples + "/concert_robot_18slaves.yaml");
  Bench bench(a, catalog);
  Master master(bench.link, quick());
  const auto real = topology::load_scan(test_data::kRealScans + "/concert_robot_18slaves.yaml");
  EXPECT_EQ(master.scan().scan(), real);
}

TEST(MasterRing, ScansSeededRandomRobots) {
  const EscCatalog catalog = EscCatalog::load(test_data::kProjectDb);
  for (unsigned seed = 1; seed <= 20; ++seed) {
    SCOPED_TRACE(seed);
    std::mt19937 rng(seed);
    const Assembly a = simbus::random_robot(rng);
    Bench bench(a, catalog, RingParams{.eeprom_8_byte_reads = seed % 2 == 0});
    Master master(bench.link, quick());
    EXPECT_EQ(master.scan().scan(), simbus::simulate_scan(a, catalog));
  }
}

TEST(MasterRing, FaultsReadAsTheSimulatedBusReportsThem) {
  const EscCatalog catalog = EscCatalog::load(test_data::kPublicDb);
  const Assembly a = simbus::parse_assembly(R"(
modules:
  - {name: base, key: mobile_platform_concert, robot_id: [100, 101]}
  - {name: yaw_1, key: module_joint_yaw_A_concert, parent: base, connector: 5, robot_id: 51}
  - {name: elbow_1, key: module_joint_elbow_A_concert, parent: yaw_1, connector: 1, robot_id: 52}
  - {name: link_1, key: module_link_straight_400_concert, parent: elbow_1, connector: 1}
  - {name: drill, key: module_drill_concert, parent: link_1, connector: 1, robot_id: 60}
faults:
  - {type: unknown_identity, module: base, esc: 1}
  - {type: wrong_topology, module: yaw_1, topology: 3}
  - {type: wrong_topology, module: link_1, topology: 1}
  - {type: broken_link, module: drill}
)", "faults");
  Bench bench(a, catalog);
  Master master(bench.link, quick());
  const topology::EscScan scan = master.scan().scan();
  EXPECT_EQ(scan, simbus::simulate_scan(a, catalog));
  ASSERT_EQ(scan.slaves.size(), 5u);
}

TEST(MasterRing, ResendsALostFrame) {
  const EscCatalog catalog = EscCatalog::load(test_data::kPublicDb);
  const Assembly a = simbus::load_assembly(test_data::kExamples + "/concert_paper_robot.yaml");
  Bench bench(a, catalog);
  bench.drop_first = 2;
  Master master(bench.link, quick());
  const ScanReport report = master.scan();
  EXPECT_EQ(report.frames_lost, 2);
  EXPECT_EQ(report.scan(), simbus::simulate_scan(a, catalog));
}

TEST(MasterRing, SaysSoWhenNothingAnswers) {
  const EscCatalog catalog = EscCatalog::load(test_data::kPublicDb);
  Assembly a = simbus::load_assembly(test_data::kExamples + "/concert_paper_robot.yaml");
  a.faults.push_back({.type = simbus::FaultType::kBrokenLink, .module = "base"});
  Bench bench(a, catalog);
  Master master(bench.link, quick());
  try {
    master.scan();
    FAIL() << "no error";
  } catch (const MasterError& e) {
    EXPECT_NE(std::string(e.what()).find("no EtherCAT frame came back on in-process ring (BRD 0x0000, 3 tries"),
              std::string::npos)
        << e.what();
  }
  EXPECT_EQ(master.frames_lost(), 3);
}

TEST(MasterRing, TheRingDropsNoiseAndKeepsAnswering) {
  const EscCatalog catalog = EscCatalog::load(test_data::kPublicDb);
  const Assembly a = simbus::load_assembly(test_data::kExamples + "/concert_paper_robot.yaml");
  Bench bench(a, catalog);
  std::mt19937 rng(5);
  std::uniform_int_distribution<int> byte(0, 255), size(14, 1600);
  uint64_t answered = 0;
  for (int i = 0; i < 2000; ++i) {
    std::vector<uint8_t> noise(static_cast<std::size_t>(size(rng)));
    for (auto& x : noise) x = static_cast<uint8_t>(byte(rng));
    noise[12] = 0x88;
    noise[13] = 0xA4;
    if (i % 4 == 0 && noise.size() > 16) {
      // A header that claims the whole frame: decodes more often, some past 1514 bytes.
      const auto length = static_cast<uint16_t>(std::min<std::size_t>(noise.size() - 16, 0x7FF));
      noise[14] = static_cast<uint8_t>(length & 0xFF);
      noise[15] = static_cast<uint8_t>(0x10 | (length >> 8));
    }
    if (bench.ring.process(noise, 0)) ++answered;
  }
  // Every frame is answered or dropped as malformed, never anything else (no throw, no crash).
  EXPECT_EQ(bench.ring.counters().malformed + answered, 2000u);
  EXPECT_GT(bench.ring.counters().malformed, 0u);
  Master master(bench.link, quick());
  EXPECT_EQ(master.scan().scan(), simbus::simulate_scan(a, catalog));
}

TEST(MasterRing, RefusesAnInvalidStateChangeByName) {
  const EscCatalog catalog = EscCatalog::load(test_data::kPublicDb);
  const Assembly a = simbus::load_assembly(test_data::kExamples + "/concert_paper_robot.yaml");
  Bench bench(a, catalog);
  Master master(bench.link, quick());
  (void)master.scan();
  // INIT -> OP skips PRE-OP and SAFE-OP: the ESC keeps INIT and flags error 0x0011.
  master.exchange({make_datagram(Command::kFpwr, 0x1003, esc::kAlControl,
                                 bytes16(static_cast<uint16_t>(esc::AlState::kOp)))});
  const auto status = master.exchange({make_datagram(Command::kFprd, 0x1003, esc::kAlStatus, 6)});
  EXPECT_EQ(read16(status[0].data), static_cast<uint16_t>(esc::AlState::kInit) | esc::kAlErrorBit);
  EXPECT_EQ(esc::al_status_code_name(read16(status[0].data, 4)), "invalid requested state change");
}

}  // namespace
}  // namespace concert::ethercat
