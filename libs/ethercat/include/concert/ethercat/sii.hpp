#pragma once
// What a CONCERT board keeps in its SII EEPROM, and where: the one mapping between the fields of
// a scan (libs/topology EscSlave) and the EEPROM (ETG.2010 layout).
//
//  * ESC type (`esc_type`, the board type: 21 joint and wheel boards, 1280 passive links, 50 and
//    256 the Mobile Base Hub's boards): the SII product code, words 0x000A-0x000B;
//  * vendor id, revision, serial number: words 0x0008, 0x000C, 0x000E (reported, not used by
//    discovery);
//  * the module identity (mod_type, mod_id, mod_size, mod_rev) and `robot_id`: a category of type
//    0x0800 ("CONCERT module", in ETG.2010's vendor-specific range 0x0800-0x0FFF), 10 words:
//    five little-endian int32 in that order.
//
// The real boards may keep the module identity elsewhere (their firmware's CoE objects); this
// mapping is ours, and the master reads it through the ESC's EEPROM interface (registers
// 0x0502-0x050F), which needs no mailbox and works in INIT.

#include <cstdint>
#include <optional>
#include <span>
#include <stdexcept>
#include <string>
#include <vector>

#include "concert/topology/types.hpp"

namespace concert::ethercat {

inline constexpr uint16_t kSiiCategoryConcertModule = 0x0800;
inline constexpr uint16_t kSiiConcertModuleWords = 10;
inline constexpr uint16_t kSiiCategorySyncManagers = 41;  ///< SyncM
inline constexpr uint16_t kSiiCategoryTxPdo = 50;         ///< inputs
inline constexpr uint16_t kSiiCategoryRxPdo = 51;         ///< outputs

/// A sync manager as the SII describes it (SyncM category, 8 bytes each).
struct SiiSyncManager {
  enum Type : uint8_t { kUnused = 0, kMailboxOut = 1, kMailboxIn = 2, kOutputs = 3, kInputs = 4 };
  uint16_t start = 0;   ///< physical start address in the ESC
  uint16_t length = 0;  ///< bytes (0 for process data: the PDOs give it)
  uint8_t control = 0;  ///< the value for register 0x0804 + 8 n
  uint8_t enable = 0;   ///< bit 0: the sync manager is used
  uint8_t type = kUnused;
  bool operator==(const SiiSyncManager&) const = default;
};

/// One entry of a PDO (8 bytes in the SII).
struct SiiPdoEntry {
  uint16_t index = 0;
  uint8_t subindex = 0;
  uint8_t data_type = 0;  ///< ETG.1000.6 type code (EntryType)
  uint8_t bits = 0;
  bool operator==(const SiiPdoEntry&) const = default;
};

/// A PDO (TxPDO or RxPDO category): its entries and the sync manager it is assigned to.
struct SiiPdo {
  uint16_t index = 0;
  uint8_t sync_manager = 0;
  std::vector<SiiPdoEntry> entries;
  /// Sum of the entries' bits.
  uint32_t bits() const;
  bool operator==(const SiiPdo&) const = default;
};

/// The fields of one board's SII EEPROM that the master reads.
struct SiiInfo {
  uint32_t vendor_id = 0;
  uint32_t product_code = 0;  ///< the board's ESC type
  uint32_t revision = 0;
  uint32_t serial = 0;
  /// Empty when the EEPROM has no CONCERT module category (a board from elsewhere).
  std::optional<topology::EscIdentity> module;
  int32_t robot_id = -1;
  std::vector<SiiSyncManager> sync_managers;  ///< SM 0, 1, ... in order
  std::vector<SiiPdo> rx_pdos;                ///< outputs (master -> board)
  std::vector<SiiPdo> tx_pdos;                ///< inputs (board -> master)

  /// Bytes of process data the board takes (outputs) and returns (inputs): the PDOs' bits
  /// rounded up to whole bytes.
  std::size_t output_bytes() const;
  std::size_t input_bytes() const;
  /// The sync manager of `type` (kOutputs, kInputs): its number, or -1.
  int sync_manager_of(uint8_t type) const;
  bool operator==(const SiiInfo&) const = default;
};

/// An EEPROM image (16-bit words) holding `identity` in the layout above: the ESC configuration
/// area (words 0x0000-0x0007, with the checksum ETG.2010 defines over words 0-6), the identity
/// words, and the category list from word 0x0040 ending in 0xFFFF.
std::vector<uint16_t> make_sii_image(const SiiInfo& identity);

/// An EEPROM image that cannot be read as above; what() names the word address.
class SiiError : public std::runtime_error {
 public:
  using std::runtime_error::runtime_error;
};

/// Reads an image (words from address 0 on). Throws SiiError when the category list runs past
/// the words given or a CONCERT module category has the wrong size.
SiiInfo parse_sii_image(std::span<const uint16_t> words);

/// True when `words` (from address 0) hold the whole category list, up to its 0xFFFF end, so
/// parse_sii_image can read them; false when more words must be read first.
bool sii_image_complete(std::span<const uint16_t> words);

/// The CRC-8 (polynomial 0x07, initial 0xFF) ETG.2010 defines over the configuration area's
/// first 14 bytes.
uint8_t sii_checksum(std::span<const uint16_t> words);

}  // namespace concert::ethercat
