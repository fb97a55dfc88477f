#pragma once
// The MCAP record layer shared by the writer and the reader: opcodes, little-endian field
// encoding (Out) and decoding with bounds checks (In), CRC-32 and chunk compression.

#include <array>
#include <cstdint>
#include <span>
#include <string>
#include <string_view>
#include <vector>

#include "concert/bag/mcap.hpp"

namespace concert::bag::detail {

enum Opcode : uint8_t {
  kHeader = 0x01,
  kFooter = 0x02,
  kSchema = 0x03,
  kChannel = 0x04,
  kMessage = 0x05,
  kChunk = 0x06,
  kMessageIndex = 0x07,
  kChunkIndex = 0x08,
  kAttachment = 0x09,
  kAttachmentIndex = 0x0A,
  kStatistics = 0x0B,
  kMetadata = 0x0C,
  kMetadataIndex = 0x0D,
  kSummaryOffset = 0x0E,
  kDataEnd = 0x0F,
};

/// "\x89MCAP0\r\n": the first and last 8 bytes of a file.
inline constexpr std::array<uint8_t, 8> kMagic = {0x89, 'M', 'C', 'A', 'P', '0', '\r', '\n'};
/// opcode (1) + content length (8)
inline constexpr uint64_t kRecordPrefix = 9;
/// A Footer record: prefix + summary_start + summary_offset_start + summary_crc.
inline constexpr uint64_t kFooterSize = kRecordPrefix + 8 + 8 + 4;

/// "Chunk", "Message", ... or "unknown record 0x42".
std::string record_name(uint8_t opcode);

/// CRC-32 (zlib's) of `bytes` continuing `crc` (0 to start).
uint32_t crc32(uint32_t crc, std::span<const uint8_t> bytes);

/// Appends little-endian fields to a byte vector.
class Out {
 public:
  explicit Out(std::vector<uint8_t>& bytes) : bytes_(bytes) {}
  void u8(uint8_t v) { bytes_.push_back(v); }
  void u16(uint16_t v) { le(v, 2); }
  void u32(uint32_t v) { le(v, 4); }
  void u64(uint64_t v) { le(v, 8); }
  /// uint32 length + bytes.
  void str(std::string_view s);
  void raw(std::span<const uint8_t> bytes) {
    bytes_.insert(bytes_.end(), bytes.begin(), bytes.end());
  }
  void map(const KeyValues& m);
  void map(const std::map<uint16_t, uint64_t>& m);
  /// Starts a record: opcode and a length patched by end_record(); returns its start.
  size_t begin_record(Opcode op);
  void end_record(size_t start);

 private:
  void le(uint64_t v, int n) {
    for (int i = 0; i < n; ++i) bytes_.push_back(static_cast<uint8_t>(v >> (8 * i)));
  }
  std::vector<uint8_t>& bytes_;
};

/// Reads the fields of one record's content; a field that does not fit throws BagError naming
/// `where` (file, record and offset) and the field.
class In {
 public:
  In(std::span<const uint8_t> content, std::string where)
      : bytes_(content), where_(std::move(where)) {}
  uint8_t u8(const char* field) { return static_cast<uint8_t>(le(1, field)); }
  uint16_t u16(const char* field) { return static_cast<uint16_t>(le(2, field)); }
  uint32_t u32(const char* field) { return static_cast<uint32_t>(le(4, field)); }
  uint64_t u64(const char* field) { return le(8, field); }
  std::string str(const char* field);
  /// `n` bytes.
  std::span<const uint8_t> bytes(uint64_t n, const char* field);
  /// Everything left.
  std::span<const uint8_t> rest();
  KeyValues string_map(const char* field);
  std::map<uint16_t, uint64_t> id_map(const char* field);
  [[noreturn]] void fail(const std::string& what) const;

 private:
  uint64_t le(int n, const char* field);
  void need(uint64_t n, const char* field);
  std::span<const uint8_t> bytes_;
  size_t pos_ = 0;
  std::string where_;
};

void put_schema(Out& out, const Schema& schema);
void put_channel(Out& out, const Channel& channel);
Schema read_schema(In& in);
Channel read_channel(In& in);
Statistics read_statistics(In& in);
ChunkIndex read_chunk_index(In& in);

/// Compresses `in` into `out` (replaced); `zstd_context` holds a reused ZSTD_CCtx (created on
/// first use, freed by free_zstd()).
void compress(Compression compression, std::span<const uint8_t> in, std::vector<uint8_t>& out,
              void*& zstd_context);
void free_zstd(void* zstd_context);
/// Decompresses a chunk's records ("", "zstd" or "lz4") of known size; `where` names the chunk.
std::vector<uint8_t> decompress(const std::string& compression, std::span<const uint8_t> in,
                                uint64_t uncompressed_size, const std::string& where);

}  // namespace concert::bag::detail
