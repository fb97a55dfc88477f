#pragma once
// EtherCAT frames on Ethernet (ETG.1000.4, "EtherCAT frame structure"; ET1100 datasheet section I,
// "Frame processing"): Ethernet header, EtherType 0x88A4, a 2-byte EtherCAT header (length: 11
// bits, type: 4 bits, 1 = datagrams), then datagrams, each a 10-byte header, data and a 16-bit
// working counter. Little-endian throughout. Written here because Debian 12 packages no EtherCAT
// master (no SOEM, no IgH); the layout is what SOEM's ethercattype.h and Wireshark's
// packet-ethercat-datagram.c read.

#include <array>
#include <cstddef>
#include <cstdint>
#include <span>
#include <stdexcept>
#include <string>
#include <string_view>
#include <vector>

namespace concert::ethercat {

inline constexpr uint16_t kEtherType = 0x88A4;
inline constexpr std::size_t kEthernetHeaderBytes = 14;
inline constexpr std::size_t kEthercatHeaderBytes = 2;
inline constexpr std::size_t kDatagramHeaderBytes = 10;
inline constexpr std::size_t kWorkingCounterBytes = 2;
/// Shortest Ethernet frame without its FCS: shorter frames are padded with zeros.
inline constexpr std::size_t kMinFrameBytes = 60;
/// Longest Ethernet frame without its FCS (1500 bytes of payload).
inline constexpr std::size_t kMaxFrameBytes = 1514;
/// The most data one frame's datagrams can carry together (1500 - EtherCAT header - one
/// datagram's header and counter).
inline constexpr std::size_t kMaxDatagramData =
    1500 - kEthercatHeaderBytes - kDatagramHeaderBytes - kWorkingCounterBytes;

/// Datagram commands (ETG.1000.4 table "EtherCAT command types").
enum class Command : uint8_t {
  kNop = 0,
  kAprd = 1,   ///< auto-increment physical read (addressed by ring position)
  kApwr = 2,
  kAprw = 3,
  kFprd = 4,   ///< configured address physical read (addressed by station address)
  kFpwr = 5,
  kFprw = 6,
  kBrd = 7,    ///< broadcast read: every slave ORs its registers into the data
  kBwr = 8,
  kBrw = 9,
  kLrd = 10,   ///< logical read, through the slaves' FMMUs
  kLwr = 11,
  kLrw = 12,
  kArmw = 13,  ///< auto-increment read, multiple write
  kFrmw = 14,
};

/// "APRD", "LRW", ...; "command 15" for a value that is none.
std::string to_string(Command command);

/// True for the commands a slave reads memory for (xPRD, xPRW, BRD, BRW, LRD, LRW, ARMW, FRMW).
bool reads(Command command);
/// True for the commands a slave writes memory for (xPWR, xPRW, BWR, BRW, LWR, LRW).
bool writes(Command command);

using MacAddress = std::array<uint8_t, 6>;

/// One datagram. For the logical commands the 32-bit logical address is ADP (low word) and
/// ADO (high word), as on the wire.
struct Datagram {
  Command command = Command::kNop;
  uint8_t index = 0;      ///< the master's number, returned unchanged
  uint16_t adp = 0;       ///< position (auto-increment, as 0 - position) or station address
  uint16_t ado = 0;       ///< register offset
  bool circulated = false;  ///< the C bit: the frame has gone round once already
  uint16_t irq = 0;
  std::vector<uint8_t> data;
  uint16_t wkc = 0;       ///< working counter: slaves add 1 per read, 2 per write

  uint32_t logical_address() const { return adp | (static_cast<uint32_t>(ado) << 16); }
  void set_logical_address(uint32_t address) {
    adp = static_cast<uint16_t>(address & 0xFFFF);
    ado = static_cast<uint16_t>(address >> 16);
  }
  bool operator==(const Datagram&) const = default;
};

/// An Ethernet frame carrying EtherCAT datagrams.
struct Frame {
  MacAddress destination{0xFF, 0xFF, 0xFF, 0xFF, 0xFF, 0xFF};
  MacAddress source{0x02, 0x00, 0x00, 0x00, 0x00, 0x01};
  std::vector<Datagram> datagrams;
  bool operator==(const Frame&) const = default;
};

/// A frame that cannot be encoded or decoded; what() names the datagram and the field.
class FrameError : public std::runtime_error {
 public:
  using std::runtime_error::runtime_error;
};

/// Bytes of the frame on the wire (without the FCS), padded to kMinFrameBytes.
std::size_t encoded_size(const Frame& frame);

/// The frame's bytes. Throws FrameError when its datagrams do not fit one Ethernet frame or one
/// datagram's data exceeds the 11-bit length field.
std::vector<uint8_t> encode(const Frame& frame);

/// Encodes into `out` (at least encoded_size bytes), for callers that must not allocate.
/// Returns the bytes written. Throws FrameError as encode().
std::size_t encode_into(const Frame& frame, std::span<uint8_t> out);

/// Reads a frame. Throws FrameError naming what is wrong and at which byte: not EtherType
/// 0x88A4, an EtherCAT header that is not type 1 or longer than the frame, a datagram that
/// runs past the header's length, a "more" bit on the last datagram.
Frame decode(std::span<const uint8_t> bytes);

/// "02:00:00:00:00:01".
std::string to_string(const MacAddress& mac);

}  // namespace concert::ethercat
