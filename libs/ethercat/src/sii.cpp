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

std::vector<uint16_t> make_sii_image(const SiiInfo& identity) {
  std::vector<uint16_t> w(esc::kSiiFirstCategory, 0);
  w[7] = sii_checksum(w);
  put32(w, esc::kSiiVendorId, identity.vendor_id);
  put32(w, esc::kSiiProductCode, identity.product_code);
  put32(w, esc::kSiiRevision, identity.revision);
  put32(w, esc::kSiiSerial, identity.serial);
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
  if (!identity.sync_managers.empty()) {
    w.push_back(kSiiCategorySyncManagers);
    w.push_back(static_cast<uint16_t>(4 * identity.sync_managers.size()));
    for (const SiiSyncManager& sm : identity.sync_managers) {
      w.push_back(sm.start);
      w.push_back(sm.length);
      w.push_back(static_cast<uint16_t>(sm.control | (0 << 8)));  // control, status (0)
      w.push_back(static_cast<uint16_t>(sm.enable | (sm.type << 8)));
    }
  }
  // One category per direction holding all its PDOs (as SOEM's ec_siiPDO reads them).
  const auto pdos = [&w](uint16_t category, const std::vector<SiiPdo>& list) {
    if (list.empty()) return;
    std::size_t size = 0;
    for (const SiiPdo& pdo : list) size += 4 + 4 * pdo.entries.size();
    w.push_back(category);
    w.push_back(static_cast<uint16_t>(size));
    for (const SiiPdo& pdo : list) {
      w.push_back(pdo.index);
      w.push_back(static_cast<uint16_t>(pdo.entries.size() | (pdo.sync_manager << 8)));
      w.push_back(0);  // synchronization, name index
      w.push_back(0);  // flags
      for (const SiiPdoEntry& e : pdo.entries) {
        w.push_back(e.index);
        w.push_back(e.subindex);  // subindex, name index 0
        w.push_back(static_cast<uint16_t>(e.data_type | (e.bits << 8)));
        w.push_back(0);  // flags
      }
    }
  };
  pdos(kSiiCategoryTxPdo, identity.tx_pdos);
  pdos(kSiiCategoryRxPdo, identity.rx_pdos);
  w.push_back(esc::kSiiCategoryEnd);
  // EEPROM size (word 0x003E): KiBit - 1 of the smallest part holding the image.
  const std::size_t kibit = (w.size() * 16 + 1023) / 1024;
  w[0x003E] = static_cast<uint16_t>(kibit - 1);
  return w;
}

uint32_t SiiPdo::bits() const {
  uint32_t sum = 0;
  for (const SiiPdoEntry& e : entries) sum += e.bits;
  return sum;
}

std::size_t SiiInfo::output_bytes() const {
  uint32_t bits = 0;
  for (const SiiPdo& p : rx_pdos) bits += p.bits();
  return (bits + 7) / 8;
}

std::size_t SiiInfo::input_bytes() const {
  uint32_t bits = 0;
  for (const SiiPdo& p : tx_pdos) bits += p.bits();
  return (bits + 7) / 8;
}

int SiiInfo::sync_manager_of(uint8_t type) const {
  for (std::size_t i = 0; i < sync_managers.size(); ++i) {
    if (sync_managers[i].type == type && (sync_managers[i].enable & 1)) return static_cast<int>(i);
  }
  return -1;
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

SiiInfo parse_sii_image(std::span<const uint16_t> words) {
  if (words.size() <= esc::kSiiFirstCategory) {
    throw SiiError("SII image of " + std::to_string(words.size()) +
                   " words ends before the category list (word 0x0040)");
  }
  SiiInfo id;
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
    } else if (type == kSiiCategorySyncManagers) {
      if (size % 4 != 0) {
        throw SiiError("SII SyncM category at word " + hex(at) + " has " + std::to_string(size) +
                       " words, not a multiple of 4");
      }
      for (std::size_t k = at + 2; k < at + 2 + size; k += 4) {
        SiiSyncManager sm;
        sm.start = words[k];
        sm.length = words[k + 1];
        sm.control = static_cast<uint8_t>(words[k + 2] & 0xFF);
        sm.enable = static_cast<uint8_t>(words[k + 3] & 0xFF);
        sm.type = static_cast<uint8_t>(words[k + 3] >> 8);
        id.sync_managers.push_back(sm);
      }
    } else if (type == kSiiCategoryTxPdo || type == kSiiCategoryRxPdo) {
      // One or more PDOs, each a 4-word header and 4 words per entry.
      for (std::size_t k = at + 2; k < at + 2 + size;) {
        if (k + 4 > at + 2 + size) {
          throw SiiError("SII PDO category at word " + hex(at) + ": a PDO header at word " + hex(k) +
                         " runs past the category's " + std::to_string(size) + " words");
        }
        SiiPdo pdo;
        pdo.index = words[k];
        const std::size_t count = words[k + 1] & 0xFF;
        pdo.sync_manager = static_cast<uint8_t>(words[k + 1] >> 8);
        if (k + 4 + 4 * count > at + 2 + size) {
          throw SiiError("SII PDO " + hex(pdo.index) + " at word " + hex(k) + ": " + std::to_string(count) +
                         " entries run past the category's " + std::to_string(size) + " words");
        }
        for (std::size_t e = k + 4; e < k + 4 + 4 * count; e += 4) {
          SiiPdoEntry entry;
          entry.index = words[e];
          entry.subindex = static_cast<uint8_t>(words[e + 1] & 0xFF);
          entry.data_type = static_cast<uint8_t>(words[e + 2] & 0xFF);
          entry.bits = static_cast<uint8_t>(words[e + 2] >> 8);
          pdo.entries.push_back(entry);
        }
        k += 4 + 4 * count;
        (type == kSiiCategoryTxPdo ? id.tx_pdos : id.rx_pdos).push_back(std::move(pdo));
      }
    }
    at += 2 + size;
  }
  return id;
}

}  // namespace concert::ethercat
