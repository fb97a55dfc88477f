// Process data through the master and the virtual ring: SII sync managers and PDOs, FMMUs,
// the AL states up to OP, the cyclic LRW and its working counter.

#include <gtest/gtest.h>

#include <cstring>

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
    ring.set_application([](int position, const BoardProcessData& board, esc::AlState state,
                            std::span<const uint8_t> out, std::span<uint8_t> in, uint64_t) {
      if (state == esc::AlState::kOp) {
        put_float(in, board.input("link_position")->offset, get_float(out, board.output("position_ref")->offset));
        put_float(in, board.input("torque")->offset, get_float(out, board.output("torque_ff")->offset));
      }
      put_float(in, board.input("board_temperature")->offset, static_cast<float>(position));
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
