#include "concert/ethercat/frame.hpp"

#include <cstdio>
#include <cstring>

namespace concert::ethercat {
namespace {

constexpr uint16_t kLengthMask = 0x07FF;     // datagram and EtherCAT header: 11-bit length
constexpr uint16_t kCirculatedBit = 0x4000;  // datagram length field, bit 14
constexpr uint16_t kMoreBit = 0x8000;        // datagram length field, bit 15: another follows
constexpr uint16_t kTypeDatagrams = 1;       // EtherCAT header bits 12..15

uint16_t get16(std::span<const uint8_t> b, std::size_t at) {
  return static_cast<uint16_t>(b[at] | (b[at + 1] << 8));
}
void put16(std::span<uint8_t> b, std::size_t at, uint16_t v) {
  b[at] = static_cast<uint8_t>(v & 0xFF);
  b[at + 1] = static_cast<uint8_t>(v >> 8);
}

std::size_t payload_size(const Frame& frame) {
  std::size_t n = kEthercatHeaderBytes;
  for (const Datagram& d : frame.datagrams) {
    n += kDatagramHeaderBytes + d.data.size() + kWorkingCounterBytes;
  }
  return n;
}

}  // namespace

std::string to_string(Command command) {
  static constexpr std::array<const char*, 15> kNames{
      "NOP", "APRD", "APWR", "APRW", "FPRD", "FPWR", "FPRW", "BRD",
      "BWR", "BRW",  "LRD",  "LWR",  "LRW",  "ARMW", "FRMW"};
  const auto value = static_cast<std::size_t>(command);
  return value < kNames.size() ? kNames[value] : "command " + std::to_string(value);
}

bool reads(Command c) {
  switch (c) {
    case Command::kAprd: case Command::kAprw: case Command::kFprd: case Command::kFprw:
    case Command::kBrd: case Command::kBrw: case Command::kLrd: case Command::kLrw:
    case Command::kArmw: case Command::kFrmw:
      return true;
    default:
      return false;
  }
}

bool writes(Command c) {
  switch (c) {
    case Command::kApwr: case Command::kAprw: case Command::kFpwr: case Command::kFprw:
    case Command::kBwr: case Command::kBrw: case Command::kLwr: case Command::kLrw:
      return true;
    default:
      return false;
  }
}

std::size_t encoded_size(const Frame& frame) {
  return std::max(kMinFrameBytes, kEthernetHeaderBytes + payload_size(frame));
}

std::size_t encode_into(const Frame& frame, std::span<uint8_t> out) {
  if (frame.datagrams.empty()) throw FrameError("an EtherCAT frame needs at least one datagram");
  const std::size_t payload = payload_size(frame);
  if (kEthernetHeaderBytes + payload > kMaxFrameBytes) {
    throw FrameError("datagrams of " + std::to_string(payload) +
                     " bytes do not fit one Ethernet frame (1500 bytes of payload)");
  }
  const std::size_t size = encoded_size(frame);
  if (out.size() < size) {
    throw FrameError("buffer of " + std::to_string(out.size()) + " bytes for a frame of " +
                     std::to_string(size));
  }
  std::memcpy(out.data(), frame.destination.data(), 6);
  std::memcpy(out.data() + 6, frame.source.data(), 6);
  out[12] = static_cast<uint8_t>(kEtherType >> 8);  // EtherType is big-endian, as in Ethernet
  out[13] = static_cast<uint8_t>(kEtherType & 0xFF);
  put16(out, 14, static_cast<uint16_t>((payload - kEthercatHeaderBytes) | (kTypeDatagrams << 12)));
  std::size_t at = kEthernetHeaderBytes + kEthercatHeaderBytes;
  for (std::size_t i = 0; i < frame.datagrams.size(); ++i) {
    const Datagram& d = frame.datagrams[i];
    if (d.data.size() > kLengthMask) {
      throw FrameError("datagram " + std::to_string(i + 1) + " (" + to_string(d.command) +
                       "): " + std::to_string(d.data.size()) +
                       " bytes of data exceed the 11-bit length field");
    }
    out[at] = static_cast<uint8_t>(d.command);
    out[at + 1] = d.index;
    put16(out, at + 2, d.adp);
    put16(out, at + 4, d.ado);
    uint16_t length = static_cast<uint16_t>(d.data.size());
    if (d.circulated) length |= kCirculatedBit;
    if (i + 1 < frame.datagrams.size()) length |= kMoreBit;
    put16(out, at + 6, length);
    put16(out, at + 8, d.irq);
    if (!d.data.empty()) std::memcpy(out.data() + at + 10, d.data.data(), d.data.size());
    at += kDatagramHeaderBytes + d.data.size();
    put16(out, at, d.wkc);
    at += kWorkingCounterBytes;
  }
  std::memset(out.data() + at, 0, size - at);
  return size;
}

std::vector<uint8_t> encode(const Frame& frame) {
  std::vector<uint8_t> bytes(encoded_size(frame));
  encode_into(frame, bytes);
  return bytes;
}

Frame decode(std::span<const uint8_t> bytes) {
  if (bytes.size() < kEthernetHeaderBytes + kEthercatHeaderBytes) {
    throw FrameError("frame of " + std::to_string(bytes.size()) +
                     " bytes is shorter than the Ethernet and EtherCAT headers (16)");
  }
  const uint16_t ether_type = static_cast<uint16_t>((bytes[12] << 8) | bytes[13]);
  if (ether_type != kEtherType) {
    char text[8];
    std::snprintf(text, sizeof text, "0x%04X", ether_type);
    throw FrameError(std::string("EtherType ") + text + " at byte 12 is not EtherCAT (0x88A4)");
  }
  Frame frame;
  std::memcpy(frame.destination.data(), bytes.data(), 6);
  std::memcpy(frame.source.data(), bytes.data() + 6, 6);
  const uint16_t header = get16(bytes, 14);
  const unsigned type = header >> 12;
  if (type != kTypeDatagrams) {
    throw FrameError("EtherCAT header type " + std::to_string(type) +
                     " at byte 14 is not 1 (datagrams)");
  }
  const std::size_t length = header & kLengthMask;
  const std::size_t end = kEthernetHeaderBytes + kEthercatHeaderBytes + length;
  if (end > bytes.size()) {
    throw FrameError("EtherCAT header length " + std::to_string(length) + " at byte 14 runs past " +
                     "the frame's " + std::to_string(bytes.size()) + " bytes");
  }
  std::size_t at = kEthernetHeaderBytes + kEthercatHeaderBytes;
  bool more = true;
  while (more) {
    const std::size_t number = frame.datagrams.size() + 1;
    if (at + kDatagramHeaderBytes + kWorkingCounterBytes > end) {
      throw FrameError("datagram " + std::to_string(number) + " at byte " + std::to_string(at) +
                       " runs past the EtherCAT header's length (" + std::to_string(length) + ")");
    }
    Datagram d;
    d.command = static_cast<Command>(bytes[at]);
    d.index = bytes[at + 1];
    d.adp = get16(bytes, at + 2);
    d.ado = get16(bytes, at + 4);
    const uint16_t field = get16(bytes, at + 6);
    d.circulated = (field & kCirculatedBit) != 0;
    more = (field & kMoreBit) != 0;
    d.irq = get16(bytes, at + 8);
    const std::size_t data = field & kLengthMask;
    if (at + kDatagramHeaderBytes + data + kWorkingCounterBytes > end) {
      throw FrameError("datagram " + std::to_string(number) + " (" + to_string(d.command) +
                       ") at byte " + std::to_string(at) + ": " + std::to_string(data) +
                       " bytes of data run past the EtherCAT header's length (" +
                       std::to_string(length) + ")");
    }
    d.data.assign(bytes.begin() + static_cast<std::ptrdiff_t>(at + kDatagramHeaderBytes),
                  bytes.begin() + static_cast<std::ptrdiff_t>(at + kDatagramHeaderBytes + data));
    at += kDatagramHeaderBytes + data;
    d.wkc = get16(bytes, at);
    at += kWorkingCounterBytes;
    frame.datagrams.push_back(std::move(d));
  }
  return frame;
}

std::string to_string(const MacAddress& mac) {
  char text[18];
  std::snprintf(text, sizeof text, "%02x:%02x:%02x:%02x:%02x:%02x", mac[0], mac[1], mac[2],
                mac[3], mac[4], mac[5]);
  return text;
}

}  // namespace concert::ethercat
