#include <gtest/gtest.h>

#include <random>

#include "concert/ethercat/esc.hpp"
#include "concert/ethercat/frame.hpp"
#include "concert/ethercat/ring_server.hpp"
#include "concert/ethercat/sii.hpp"

namespace concert::ethercat {
namespace {

Frame two_datagrams() {
  Frame f;
  Datagram a;
  a.command = Command::kBrd;
  a.index = 7;
  a.ado = 0x0000;
  a.data = {0, 0};
  Datagram b;
  b.command = Command::kLrw;
  b.index = 7;
  b.set_logical_address(0x00010000);
  b.data = {1, 2, 3, 4, 5};
  b.wkc = 3;
  f.datagrams = {a, b};
  return f;
}

TEST(Frame, EncodesTheWireLayout) {
  const std::vector<uint8_t> bytes = encode(two_datagrams());
  ASSERT_EQ(bytes.size(), kMinFrameBytes);  // 14 + 2 + 14 + 17 = 47, padded to 60
  EXPECT_EQ(bytes[12], 0x88);
  EXPECT_EQ(bytes[13], 0xA4);
  // EtherCAT header: length 31 (two datagrams: 12 + 2 + 12 + 5), type 1.
  EXPECT_EQ(bytes[14] | (bytes[15] << 8), 31 | (1 << 12));
  EXPECT_EQ(bytes[16], 7);     // BRD
  EXPECT_EQ(bytes[17], 7);     // index
  EXPECT_EQ(bytes[22] | (bytes[23] << 8), 2 | 0x8000);  // length 2, more follows
  EXPECT_EQ(bytes[30], 12);    // LRW
  EXPECT_EQ(bytes[36] | (bytes[37] << 8), 5);           // last: no "more" bit
  EXPECT_EQ(bytes[32] | (bytes[33] << 8), 0x0000);      // logical address, low word in ADP
  EXPECT_EQ(bytes[34] | (bytes[35] << 8), 0x0001);
  EXPECT_EQ(bytes[45] | (bytes[46] << 8), 3);           // working counter
}

TEST(Frame, RoundTrips) {
  const Frame f = two_datagrams();
  EXPECT_EQ(decode(encode(f)), f);
}

TEST(Frame, RefusesWhatIsNotAnEtherCatFrame) {
  std::vector<uint8_t> bytes = encode(two_datagrams());
  auto error_of = [](std::vector<uint8_t> b) {
    try {
      decode(b);
    } catch (const FrameError& e) {
      return std::string(e.what());
    }
    return std::string("no error");
  };
  auto ip = bytes;
  ip[12] = 0x08;
  ip[13] = 0x00;
  EXPECT_EQ(error_of(ip), "EtherType 0x0800 at byte 12 is not EtherCAT (0x88A4)");
  auto mailbox = bytes;
  mailbox[15] = static_cast<uint8_t>((mailbox[15] & 0x0F) | 0x50);
  EXPECT_EQ(error_of(mailbox), "EtherCAT header type 5 at byte 14 is not 1 (datagrams)");
  auto too_long = bytes;
  too_long[14] = 0xFF;
  too_long[15] = 0x17;
  EXPECT_NE(error_of(too_long).find("runs past the frame's 60 bytes"), std::string::npos);
  auto datagram_past = bytes;
  datagram_past[36] = 40;  // the LRW's data now runs past the header's 31 bytes
  EXPECT_NE(error_of(datagram_past).find("datagram 2 (LRW) at byte 30"), std::string::npos);
  EXPECT_EQ(error_of({1, 2, 3}), "frame of 3 bytes is shorter than the Ethernet and EtherCAT headers (16)");
}

TEST(Frame, RefusesWhatDoesNotFitOneFrame) {
  Frame f;
  Datagram d;
  d.command = Command::kLrd;
  d.data.assign(kMaxDatagramData + 1, 0);
  f.datagrams = {d};
  EXPECT_THROW(encode(f), FrameError);
  f.datagrams.front().data.resize(kMaxDatagramData);
  EXPECT_EQ(encode(f).size(), kMaxFrameBytes);
  EXPECT_THROW(encode(Frame{}), FrameError);
}

TEST(Frame, NamesCommands) {
  EXPECT_EQ(to_string(Command::kLrw), "LRW");
  EXPECT_EQ(to_string(static_cast<Command>(15)), "command 15");
  EXPECT_TRUE(reads(Command::kBrw) && writes(Command::kBrw));
  EXPECT_FALSE(writes(Command::kFprd));
}

TEST(Frame, DecodeNeverCrashesOnNoise) {
  std::mt19937 rng(11);
  std::uniform_int_distribution<int> byte(0, 255), size(0, 200);
  int decoded = 0;
  for (int i = 0; i < 5000; ++i) {
    std::vector<uint8_t> b(static_cast<std::size_t>(size(rng)));
    for (auto& x : b) x = static_cast<uint8_t>(byte(rng));
    if (b.size() > 14 && i % 2 == 0) {
      b[12] = 0x88;
      b[13] = 0xA4;
      if (b.size() > 16 && i % 4 == 0) {
        // A header of type 1 claiming the rest of the frame: the datagrams decide.
        const auto length = static_cast<uint16_t>(b.size() - 16);
        b[14] = static_cast<uint8_t>(length & 0xFF);
        b[15] = static_cast<uint8_t>(0x10 | (length >> 8));
      }
    }
    try {
      const Frame f = decode(b);
      ++decoded;
      // Whatever decodes encodes back to the same frame.
      EXPECT_EQ(decode(encode(f)), f);
    } catch (const FrameError&) {
    }
  }
  // Some noise with the EtherType is a frame, most is not.
  EXPECT_GT(decoded, 0);
  EXPECT_LT(decoded, 2500);
}

TEST(Esc, ReadsPortsFromTheDlStatus) {
  // Ports 0 and 1 linked, open, communicating; 2 and 3 closed without link.
  const uint16_t dl = esc::kDlPdiOperational | esc::dl_link(0) | esc::dl_link(1) |
                      esc::dl_communication(0) | esc::dl_communication(1) |
                      esc::dl_loop_closed(2) | esc::dl_loop_closed(3);
  EXPECT_EQ(dl, 0x5A31);
  EXPECT_EQ(esc::open_ports(dl), 0b0011);
  EXPECT_EQ(esc::linked_ports(dl), 0b0011);
  // A port with a link but no communication is linked, not open.
  EXPECT_EQ(esc::open_ports(dl | esc::dl_link(2)), 0b0011);
  EXPECT_EQ(esc::linked_ports(dl | esc::dl_link(2)), 0b0111);
}

TEST(Esc, NamesAlStates) {
  EXPECT_EQ(esc::to_string(esc::AlState::kSafeOp), "SAFE-OP");
  EXPECT_EQ(esc::al_status_code_name(0x001B), "sync manager watchdog");
  EXPECT_EQ(esc::al_status_code_name(0x0011), "invalid requested state change");
  EXPECT_EQ(esc::al_status_code_name(0x1234), "unknown AL status code 0x1234");
  EXPECT_FALSE(esc::al_state_from(5));
}

TEST(Sii, ImageRoundTrips) {
  SiiInfo id;
  id.vendor_id = 0x12345678;
  id.product_code = 21;
  id.revision = 3;
  id.serial = 99;
  id.module = topology::EscIdentity{1, 6, 4, 0};
  id.robot_id = 53;
  const auto image = make_sii_image(id);
  EXPECT_TRUE(sii_image_complete(image));
  EXPECT_FALSE(sii_image_complete(std::span<const uint16_t>(image.data(), image.size() - 1)));
  EXPECT_EQ(parse_sii_image(image), id);
  EXPECT_EQ(image[7], sii_checksum(image));
  SiiInfo other;
  other.product_code = 1280;
  EXPECT_EQ(parse_sii_image(make_sii_image(other)), other);  // no module category
}

TEST(Sii, NamesWhatIsWrong) {
  SiiInfo id;
  id.module = topology::EscIdentity{1, 6, 4, 0};
  auto image = make_sii_image(id);
  image[0x41] = 4;  // the CONCERT category claims 4 words
  try {
    parse_sii_image(image);
    FAIL() << "no error";
  } catch (const SiiError& e) {
    EXPECT_EQ(std::string(e.what()), "SII CONCERT module category at word 0x0040 has 4 words, not 10");
  }
  image.pop_back();
  image[0x41] = 10;
  EXPECT_THROW(parse_sii_image(image), SiiError);
}

}  // namespace
}  // namespace concert::ethercat

namespace concert::ethercat {
namespace {

TEST(RingFaultSpec, ReadsEveryKindAndNamesWhatIsWrong) {
  const RingFault pull = parse_ring_fault("pull:elbow_2@0.5");
  EXPECT_EQ(pull.kind, RingFault::Kind::kPull);
  EXPECT_EQ(pull.module, "elbow_2");
  EXPECT_DOUBLE_EQ(pull.after_s, 0.5);
  EXPECT_EQ(parse_ring_fault("refuse-op:yaw_2:0x001B").code, 0x001B);
  EXPECT_EQ(parse_ring_fault("refuse-op:yaw_2").code, 0x001A);
  EXPECT_EQ(parse_ring_fault("lose:100").one_in, 100u);
  const auto error_of = [](const std::string& spec) {
    try {
      parse_ring_fault(spec);
    } catch (const RingFaultError& e) {
      return std::string(e.what());
    }
    return std::string("no error");
  };
  EXPECT_EQ(error_of("cut:x"), "--fault cut:x: kind 'cut' is not pull, refuse-op or lose");
  EXPECT_EQ(error_of("pull:x@soon"), "--fault pull:x@soon: seconds 'soon' is not a number >= 0");
  EXPECT_EQ(error_of("lose:1"), "--fault lose:1: lose:N needs N >= 2");
  EXPECT_EQ(error_of("pull:"), "--fault pull:: no module named");
  EXPECT_EQ(error_of("refuse-op:m:0x10000"), "--fault refuse-op:m:0x10000: AL status code '0x10000' is not 1..0xFFFF");
  EXPECT_EQ(error_of("pull"), "--fault pull: expected KIND:ARGUMENT");
}

}  // namespace
}  // namespace concert::ethercat
