#include "concert/ethercat/sii.hpp"

#include "concert/ethercat/esc.hpp"

namespace concert::ethercat {
namespace {

uint32_t get32(std::span<const uint16_t> w, std::size_t at) {
  return static_cast<uint32_t>(w[at]) | (static_cast<uint32_t>(w[at + 1]) << 16);
}
void put32(std::vector<uint16_t>& w, std::size_t at, uint32_t v) {
  w[at] = static_cast<uint16_t>(v & 0xFFFF);
  w[at + 1] = static_cast<uint16_t>(v >> 16);
}
std::string hex(std::size_t word) {
  char text[12];
  std::snprintf(text, sizeof text, "0x%04zX", word);
  return text;
}

}  // namespace

uint8_t sii_checksum(std::span<const uint16_t> words) {
  uint8_t crc = 0xFF;
  for (std::size_t i = 0; i < 7 && i < words.size(); ++i) {
    for (const uint8_t byte : {static_cast<uint8_t>(words[i] & 0xFF), static_cast<uint8_t>(words[i] >> 8)}) {
      crc ^= byte;
      for (int bit = 0; bit < 8; ++bit) {
        crc = static_cast<uint8_t>((crc & 0x80) ? (crc << 1) ^ 0x07 : (crc << 1));
      }
    }
  }
  return crc;
}

std::vector<uint16_t> make_sii_image(const SiiIdentity& identity) {
  std::vector<uint16_t> w(esc::kSiiFirstCategory, 0);
  w[7] = sii_checksum(w);
  put32(w, esc::kSiiVendorId, identity.vendor_id);
  put32(w, esc::kSiiProductCode, identity.product_code);
  put32(w, esc::kSiiRevision, identity.revision);
  put32(w, esc::kSiiSerial, identity.serial);
  w[0x003E] = 0x0000;  // EEPROM size: (0 + 1) KiBit, as the smallest parts report
  w[0x003F] = 0x0001;  // version 1
  if (identity.module) {
    w.push_back(kSiiCategoryConcertModule);
    w.push_back(kSiiConcertModuleWords);
    const std::size_t at = w.size();
    w.resize(at + kSiiConcertModuleWords);
    put32(w, at, static_cast<uint32_t>(identity.module->mod_type));
    put32(w, at + 2, static_cast<uint32_t>(identity.module->mod_id));
    put32(w, at + 4, static_cast<uint32_t>(identity.module->mod_size));
    put32(w, at + 6, static_cast<uint32_t>(identity.module->mod_rev));
    put32(w, at + 8, static_cast<uint32_t>(identity.robot_id));
  }
  w.push_back(esc::kSiiCategoryEnd);
  return w;
}

bool sii_image_complete(std::span<const uint16_t> words) {
  std::size_t at = esc::kSiiFirstCategory;
  // Bounded: each step moves past a category of at least two words.
  while (at < words.size()) {
    if (words[at] == esc::kSiiCategoryEnd) return true;
    if (at + 1 >= words.size()) return false;
    at += 2 + words[at + 1];
  }
  return false;
}

SiiIdentity parse_sii_image(std::span<const uint16_t> words) {
  if (words.size() <= esc::kSiiFirstCategory) {
    throw SiiError("SII image of " + std::to_string(words.size()) +
                   " words ends before the category list (word 0x0040)");
  }
  SiiIdentity id;
  id.vendor_id = get32(words, esc::kSiiVendorId);
  id.product_code = get32(words, esc::kSiiProductCode);
  id.revision = get32(words, esc::kSiiRevision);
  id.serial = get32(words, esc::kSiiSerial);
  std::size_t at = esc::kSiiFirstCategory;
  while (true) {
    if (at >= words.size()) {
      throw SiiError("SII category list runs past the " + std::to_string(words.size()) +
                     " words read (no 0xFFFF end before word " + hex(at) + ")");
    }
    const uint16_t type = words[at];
    if (type == esc::kSiiCategoryEnd) break;
    if (at + 1 >= words.size()) {
      throw SiiError("SII category at word " + hex(at) + " has no size word");
    }
    const std::size_t size = words[at + 1];
    if (at + 2 + size > words.size()) {
      throw SiiError("SII category " + hex(type) + " at word " + hex(at) + " of " +
                     std::to_string(size) + " words runs past the image");
    }
    if (type == kSiiCategoryConcertModule) {
      if (size != kSiiConcertModuleWords) {
        throw SiiError("SII CONCERT module category at word " + hex(at) + " has " +
                       std::to_string(size) + " words, not 10");
      }
      const std::size_t d = at + 2;
      topology::EscIdentity module;
      module.mod_type = static_cast<int32_t>(get32(words, d));
      module.mod_id = static_cast<int32_t>(get32(words, d + 2));
      module.mod_size = static_cast<int32_t>(get32(words, d + 4));
      module.mod_rev = static_cast<int32_t>(get32(words, d + 6));
      id.module = module;
      id.robot_id = static_cast<int32_t>(get32(words, d + 8));
    }
    at += 2 + size;
  }
  return id;
}

}  // namespace concert::ethercat
