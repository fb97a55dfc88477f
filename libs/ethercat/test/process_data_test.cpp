// Process data through the master and the virtual ring: SII sync managers and PDOs, FMMUs,
// the AL states up to OP, the cyclic LRW and its working counter.

#include <gtest/gtest.h>

#include <cstring>

#include "concert/ethercat/drive_pdo.hpp"
#include "concert/ethercat/master.hpp"
#include "concert/ethercat/process_data.hpp"
#include "concert/ethercat/virtual_ring.hpp"
#include "test_data.hpp"

namespace concert::ethercat {
namespace {

const std::string kProcessData = std::string(CONCERT_SOURCE_DIR) + "/data/module_db/process_data.yaml";

float get_float(std::span<const uint8_t> bytes, std::size_t at) {
  float v;
  std::memcpy(&v, bytes.data() + at, sizeof v);
  return v;
}
void put_float(std::span<uint8_t> bytes, std::size_t at, float v) { std::memcpy(bytes.data() + at, &v, sizeof v); }

struct Ring {
  topology::EscCatalog catalog = topology::EscCatalog::load(test_data::kPublicDb);
  ProcessDataCatalog process_data = ProcessDataCatalog::load(kProcessData);
  simbus::Assembly assembly = simbus::load_assembly(test_data::kExamples + "/concert_paper_robot.yaml");
  VirtualRing ring{assembly, catalog, RingParams{}, &process_data};
  uint64_t now = 0;
  bool drop = false;  // the next frames are lost
  LoopbackLink link{[this](std::span<const uint8_t> f) -> std::optional<std::vector<uint8_t>> {
    if (drop) return std::nullopt;
    return ring.process(f, now += 1'000'000);
  }};
  Master master{link, MasterParams{.frame_timeout = std::chrono::microseconds(1000),
                                   .state_poll_interval = std::chrono::microseconds(0)}};
  Ring() {
    // A test drive: the link follows the position reference at once, the torque is the
    // feed-forward, and the board reports which position it is at in the ring as temperature.
    ring.set_application([](std::span<BoardIo> boards, uint64_t) {
      for (const BoardIo& b : boards) {
        if (b.state == esc::AlState::kOp) {
          put_float(b.inputs, b.board->input("link_position")->offset,
                    get_float(b.outputs, b.board->output("position_ref")->offset));
          put_float(b.inputs, b.board->input("torque")->offset,
                    get_float(b.outputs, b.board->output("torque_ff")->offset));
        }
        put_float(b.inputs, b.board->input("board_temperature")->offset, static_cast<float>(b.position));
      }
    });
  }
};

TEST(ProcessData, TheDriveLayoutIsWhatTheFileSays) {
  const ProcessDataCatalog c = ProcessDataCatalog::load(kProcessData);
  const BoardProcessData* drive = c.find(21);
  ASSERT_NE(drive, nullptr);
  EXPECT_EQ(drive->output_bytes(), 28u);
  EXPECT_EQ(drive->input_bytes(), 28u);
  EXPECT_EQ(drive->output("max_torque")->index, 0x6072);
  EXPECT_EQ(drive->input("link_position")->offset, 4u);
  EXPECT_EQ(c.find(1280), nullptr);  // passive links exchange nothing
}

TEST(ProcessData, NamesWhatIsWrongInTheFile) {
  const auto error_of = [](const std::string& yaml) {
    try {
      ProcessDataCatalog::parse(yaml, "pd.yaml");
    } catch (const ProcessDataError& e) {
      return std::string(e.what());
    }
    return std::string("no error");
  };
  EXPECT_EQ(error_of("boards:\n  - {esc_type: 21, outputs: [{name: a, type: float64}]}\n"),
            "pd.yaml: boards[0].outputs[0]: type 'float64' is not int8, int16, int32, uint8, uint16, uint32 or float32 (line 2)");
  EXPECT_EQ(error_of("boards:\n  - {esc_type: 21}\n  - {esc_type: 21}\n"),
            "pd.yaml: boards[1]: esc_type 21 listed twice (line 3)");
  EXPECT_EQ(error_of("nothing: 1\n"), "pd.yaml: expected a list 'boards:'");
}

TEST(ProcessData, TheSiiCarriesSyncManagersAndPdos) {
  const ProcessDataCatalog c = ProcessDataCatalog::load(kProcessData);
  SiiInfo info;
  add_process_data(info, *c.find(21));
  const SiiInfo read = parse_sii_image(make_sii_image(info));
  EXPECT_EQ(read, info);
  EXPECT_EQ(read.output_bytes(), 28u);
  EXPECT_EQ(read.input_bytes(), 28u);
  EXPECT_EQ(read.sync_manager_of(SiiSyncManager::kOutputs), 2);
  EXPECT_EQ(read.sync_manager_of(SiiSyncManager::kInputs), 3);
  EXPECT_EQ(read.sync_manager_of(SiiSyncManager::kMailboxOut), -1);  // no mailbox
}

TEST(ProcessData, CyclesInOpWithTheFullWorkingCounter) {
  Ring r;
  const ScanReport report = r.master.scan();
  ProcessImage image = r.master.map_process_data(report);
  // The paper robot: 13 drive boards (4 steering, 4 wheels, 5 arm joints... and the drill).
  std::size_t drives = 0;
  for (const auto& s : report.slaves) drives += s.slave.esc_type == 21 ? 1 : 0;
  ASSERT_GT(drives, 0u);
  EXPECT_EQ(image.slaves.size(), drives);
  EXPECT_EQ(image.expected_wkc, 3 * drives);
  EXPECT_EQ(image.outputs.size(), 28 * drives);

  r.master.request_state(report, esc::AlState::kPreOp);
  // In PRE-OP no process data passes.
  EXPECT_EQ(r.master.cycle(image).wkc, 0);
  r.master.request_state(report, esc::AlState::kSafeOp);
  // In SAFE-OP the inputs pass, the outputs do not: 1 per drive.
  const CycleResult safe = r.master.cycle(image);
  EXPECT_TRUE(safe.returned);
  EXPECT_EQ(safe.wkc, drives);
  r.master.request_state(report, esc::AlState::kOp);
  const ProcessImageSlave& first = image.slaves.front();
  put_float(image.outputs, first.output_offset + 4, 0.25F);   // position_ref
  put_float(image.outputs, first.output_offset + 12, -3.5F);  // torque_ff
  EXPECT_EQ(r.master.cycle(image).wkc, image.expected_wkc);
  // The board answered the outputs of this cycle in its inputs, read by the next frame.
  EXPECT_EQ(r.master.cycle(image).wkc, image.expected_wkc);
  EXPECT_FLOAT_EQ(get_float(image.inputs, first.input_offset + 4), 0.25F);
  EXPECT_FLOAT_EQ(get_float(image.inputs, first.input_offset + 16), -3.5F);
  // Each board's inputs land at its own offset.
  for (const ProcessImageSlave& s : image.slaves) {
    EXPECT_FLOAT_EQ(get_float(image.inputs, s.input_offset + 24), static_cast<float>(s.position));
  }
}

TEST(ProcessData, ASlaveWithAWrongSyncManagerRefusesSafeOpByName) {
  Ring r;
  const ScanReport report = r.master.scan();
  ProcessImage image = r.master.map_process_data(report);
  r.master.request_state(report, esc::AlState::kPreOp);
  const ProcessImageSlave& victim = image.slaves[1];
  // Sync manager 2's length one byte short of what the SII says.
  r.master.exchange({make_datagram(Command::kFpwr, victim.station_address, esc::kSyncManager + 16 + 2,
                                   bytes16(static_cast<uint16_t>(victim.output_bytes - 1)))});
  try {
    r.master.request_state(report, esc::AlState::kSafeOp);
    FAIL() << "no error";
  } catch (const MasterError& e) {
    const std::string what = e.what();
    EXPECT_NE(what.find("slave " + std::to_string(victim.position) + " (station 0x"), std::string::npos) << what;
    EXPECT_NE(what.find("is in PRE-OP, AL status code 0x001D (invalid output configuration)"), std::string::npos) << what;
  }
}

TEST(ProcessData, ALostCycleIsCountedNotResent) {
  Ring r;
  const ScanReport report = r.master.scan();
  ProcessImage image = r.master.map_process_data(report);
  for (const auto state : {esc::AlState::kPreOp, esc::AlState::kSafeOp, esc::AlState::kOp}) {
    r.master.request_state(report, state);
  }
  const int sent = r.master.frames_sent();
  const int lost = r.master.frames_lost();
  r.drop = true;
  const CycleResult missed = r.master.cycle(image);
  EXPECT_FALSE(missed.returned);
  EXPECT_EQ(missed.wkc, 0);
  EXPECT_EQ(r.master.frames_sent(), sent + 1);  // sent once, not again
  EXPECT_EQ(r.master.frames_lost(), lost + 1);
  r.drop = false;
  EXPECT_EQ(r.master.cycle(image).wkc, image.expected_wkc);
  Master unmapped(r.link);
  EXPECT_THROW(unmapped.cycle(image), MasterError);
}

}  // namespace
}  // namespace concert::ethercat

namespace concert::ethercat {
namespace {

struct InOp : Ring {
  ScanReport report;
  ProcessImage image;
  InOp() {
    report = master.scan();
    image = master.map_process_data(report);
    for (const auto state : {esc::AlState::kPreOp, esc::AlState::kSafeOp, esc::AlState::kOp}) {
      master.request_state(report, state);
    }
  }
};

TEST(RingFaults, APulledCableShortensTheWorkingCounterAndIsNamed) {
  InOp r;
  ASSERT_EQ(r.master.cycle(r.image).wkc, r.image.expected_wkc);
  EXPECT_TRUE(r.master.diagnose(r.report).healthy());
  // The paper robot's arm from its second elbow on: elbow, yaw, link, elbow, yaw, drill.
  r.ring.pull_cable("elbow_2");
  const CycleResult cut = r.master.cycle(r.image);
  EXPECT_TRUE(cut.returned);
  EXPECT_LT(cut.wkc, r.image.expected_wkc);
  const RingDiagnosis d = r.master.diagnose(r.report);
  EXPECT_EQ(d.answering, static_cast<int>(r.report.slaves.size() - d.missing.size()));
  ASSERT_FALSE(d.missing.empty());
  ASSERT_EQ(d.links_lost.size(), 1u);
  EXPECT_EQ(d.links_lost.front().second, 1);  // the link's output port
  EXPECT_EQ(d.links_lost.front().first, d.missing.front() - 1);
  EXPECT_NE(d.text().find("do not answer (slave " + std::to_string(d.missing.front() - 1) +
                          " lost the link on port 1)"),
            std::string::npos)
      << d.text();
  // Plugged back: the boards kept their configuration and answer in OP again.
  r.ring.plug_cable("elbow_2");
  EXPECT_EQ(r.master.cycle(r.image).wkc, r.image.expected_wkc);
  EXPECT_TRUE(r.master.diagnose(r.report).missing.empty());
}

TEST(RingFaults, ASlaveRefusingOpIsNamedWithItsCode) {
  Ring r;
  const ScanReport report = r.master.scan();
  r.master.map_process_data(report);
  r.ring.refuse_op("yaw_2", 0x001A);
  for (const auto state : {esc::AlState::kPreOp, esc::AlState::kSafeOp}) r.master.request_state(report, state);
  try {
    r.master.request_state(report, esc::AlState::kOp);
    FAIL() << "no error";
  } catch (const MasterError& e) {
    EXPECT_NE(std::string(e.what()).find("is in SAFE-OP, AL status code 0x001A (synchronization error)"),
              std::string::npos)
        << e.what();
  }
  EXPECT_EQ(r.master.diagnose(report).al_errors.size(), 1u);
  EXPECT_THROW(r.ring.refuse_op("no_such_module", 0x001A), simbus::AssemblyError);
}

TEST(RingFaults, LostFramesAreLost) {
  InOp r;
  r.ring.lose_one_in(4);
  int lost = 0;
  for (int i = 0; i < 40; ++i) lost += r.master.cycle(r.image).returned ? 0 : 1;
  EXPECT_EQ(lost, 10);
  EXPECT_EQ(r.ring.counters().lost, 10u);
}

TEST(RingFaults, AModuleAddedAtRunTimeAppearsInANewScan) {
  InOp r;
  const std::size_t before = r.report.slaves.size();
  simbus::Assembly grown = r.ring.assembly();
  // A 0.4 m link between the arm's last yaw and the drill.
  for (auto& m : grown.modules) {
    if (m.name == "drill") m.parent = "extra_link";
  }
  grown.modules.push_back({.name = "extra_link", .key = "module_link_straight_400_concert",
                           .parent = "yaw_3", .connector = 1});
  r.ring.set_assembly(grown);
  // The boards behind the new one moved one position on: the station addresses still reach
  // them, but the new board has none, so a broadcast counts one more slave than was scanned.
  EXPECT_EQ(r.master.diagnose(r.report).answering, static_cast<int>(before + 1));
  Master again(r.link, MasterParams{.frame_timeout = std::chrono::microseconds(1000)});
  const ScanReport rescanned = again.scan();
  EXPECT_EQ(rescanned.scan(), simbus::simulate_scan(grown, r.catalog));
  // A bad assembly leaves the ring as it was.
  simbus::Assembly bad = grown;
  bad.modules.back().key = "no_such_key";
  EXPECT_THROW(r.ring.set_assembly(bad), simbus::AssemblyError);
  EXPECT_EQ(r.ring.slave_count(), before + 1);
}

}  // namespace
}  // namespace concert::ethercat

namespace concert::ethercat {
namespace {

TEST(DriveCodec, CarriesACommandAndFeedbackThroughTheDriveBoardsBytes) {
  const ProcessDataCatalog c = ProcessDataCatalog::load(kProcessData);
  const DriveCodec codec(*c.find(21));
  hardware::DriveCommand cmd;
  cmd.mode = hardware::DriveMode::kImpedance;
  cmd.position = 1.25;
  cmd.velocity = -0.5;
  cmd.effort = 12.0;
  cmd.stiffness = 800;
  cmd.damping = 20;
  cmd.max_effort = 140;
  std::vector<uint8_t> out(codec.output_bytes());
  codec.encode(cmd, true, out);
  EXPECT_EQ(out[0] | (out[1] << 8), kControlEnableOperation);
  EXPECT_EQ(out[2], 4);  // impedance
  bool enabled = false;
  const hardware::DriveCommand back = codec.decode_command(out, enabled);
  EXPECT_TRUE(enabled);
  EXPECT_EQ(back.mode, hardware::DriveMode::kImpedance);
  EXPECT_FLOAT_EQ(static_cast<float>(back.position), 1.25F);
  EXPECT_FLOAT_EQ(static_cast<float>(back.max_effort), 140.0F);
  codec.encode(cmd, false, out);
  codec.decode_command(out, enabled);
  EXPECT_FALSE(enabled);

  DriveFeedback f;
  f.status_word = kStatusOperationEnabled;
  f.link_position = -0.75;
  f.torque = 33.5;
  f.motor_temperature = 61;
  std::vector<uint8_t> in(codec.input_bytes());
  codec.encode(f, in);
  const DriveFeedback g = codec.decode_feedback(in);
  EXPECT_EQ(g.status_word, kStatusOperationEnabled);
  EXPECT_FLOAT_EQ(static_cast<float>(g.link_position), -0.75F);
  EXPECT_FLOAT_EQ(static_cast<float>(g.torque), 33.5F);
  EXPECT_FLOAT_EQ(static_cast<float>(g.motor_temperature), 61.0F);
}

TEST(DriveCodec, RefusesABoardThatIsNoDrive) {
  const ProcessDataCatalog c = ProcessDataCatalog::parse(
      "boards:\n  - {esc_type: 7, name: io, outputs: [{name: control_word, type: uint16}], "
      "inputs: [{name: status_word, type: uint16}]}\n",
      "pd.yaml");
  try {
    DriveCodec codec(*c.find(7));
    FAIL() << "no error";
  } catch (const ProcessDataError& e) {
    EXPECT_EQ(std::string(e.what()), "board 'io' (ESC type 7) has no output entry 'mode' a drive needs");
  }
}

}  // namespace
}  // namespace concert::ethercat
