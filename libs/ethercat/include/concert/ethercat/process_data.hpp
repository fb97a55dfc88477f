#pragma once
// The process data of each CONCERT board type (data/module_db/process_data.yaml): which entries a
// board takes every cycle (outputs, RxPDO, sync manager 2) and returns (inputs, TxPDO, sync
// manager 3), keyed by the ESC type the board reports. The virtual ring puts them in the boards'
// SII (SyncM, RxPDO and TxPDO categories); the master reads them from there, as masters do for
// slaves without a mailbox.

#include <cstdint>
#include <filesystem>
#include <optional>
#include <stdexcept>
#include <string>
#include <string_view>
#include <vector>

#include "concert/ethercat/sii.hpp"

namespace concert::ethercat {

/// Types of process data entries (ETG.1000.6 base data types, with their CoE type codes).
enum class EntryType : uint8_t {
  kInt8 = 0x02, kInt16 = 0x03, kInt32 = 0x04, kUint8 = 0x05, kUint16 = 0x06, kUint32 = 0x07,
  kFloat32 = 0x08,
};
/// Bytes of one entry of the type.
std::size_t size_of(EntryType type);
/// "uint16", ...
std::string to_string(EntryType type);

struct PdoEntry {
  std::string name;
  EntryType type = EntryType::kUint8;
  uint16_t index = 0;     ///< CoE object
  std::size_t offset = 0; ///< byte offset in the board's outputs or inputs
  bool operator==(const PdoEntry&) const = default;
};

/// One board type's process data.
struct BoardProcessData {
  int32_t esc_type = 0;
  std::string name;
  std::vector<PdoEntry> outputs;
  std::vector<PdoEntry> inputs;
  std::size_t output_bytes() const;
  std::size_t input_bytes() const;
  /// The entry called `name` among outputs or inputs, or nullptr.
  const PdoEntry* output(std::string_view name) const;
  const PdoEntry* input(std::string_view name) const;
};

/// A process data file that cannot be read; what() names the file, the line and the field.
class ProcessDataError : public std::runtime_error {
 public:
  using std::runtime_error::runtime_error;
};

class ProcessDataCatalog {
 public:
  /// Reads a process data file. Throws ProcessDataError.
  static ProcessDataCatalog load(const std::filesystem::path& file);
  /// Parses its text; `source` names it in messages. Throws ProcessDataError.
  static ProcessDataCatalog parse(std::string_view yaml, const std::string& source);

  /// The process data of boards of `esc_type`, or nullptr (a board without process data).
  const BoardProcessData* find(int32_t esc_type) const;
  const std::vector<BoardProcessData>& boards() const { return boards_; }

 private:
  static ProcessDataCatalog parse_checked(std::string_view yaml, const std::string& source);
  std::vector<BoardProcessData> boards_;
};

/// Where a board keeps its process data (the SII's SyncM category): outputs in sync manager 2 at
/// 0x1100, inputs in sync manager 3 after the outputs' three buffers; sync managers 0 and 1 are
/// the (unused: no mailbox) mailbox pair.
inline constexpr uint16_t kOutputsStart = 0x1100;

/// Adds `board`'s sync managers and PDOs (RxPDO 0x1600 on SM 2, TxPDO 0x1A00 on SM 3) to `sii`.
void add_process_data(SiiInfo& sii, const BoardProcessData& board);

}  // namespace concert::ethercat
