#include "records.hpp"

#include <lz4frame.h>
#include <zlib.h>
#include <zstd.h>

#include <limits>

namespace concert::bag::detail {

std::string record_name(uint8_t opcode) {
  static constexpr std::array<const char*, 16> kNames = {
      "",           "Header",           "Footer",
      "Schema",     "Channel",          "Message",
      "Chunk",      "Message Index",    "Chunk Index",
      "Attachment", "Attachment Index", "Statistics",
      "Metadata",   "Metadata Index",   "Summary Offset",
      "Data End"};
  if (opcode >= 1 && opcode < kNames.size()) return kNames[opcode];
  static const char* digits = "0123456789abcdef";
  return std::string("unknown record 0x") + digits[opcode >> 4] + digits[opcode & 15];
}

uint32_t crc32(uint32_t crc, std::span<const uint8_t> bytes) {
  return static_cast<uint32_t>(::crc32_z(crc, bytes.data(), bytes.size()));
}

void Out::str(std::string_view s) {
  u32(static_cast<uint32_t>(s.size()));
  bytes_.insert(bytes_.end(), s.begin(), s.end());
}

void Out::map(const KeyValues& m) {
  uint64_t size = 0;
  for (const auto& [k, v] : m) size += 8 + k.size() + v.size();
  u32(static_cast<uint32_t>(size));
  for (const auto& [k, v] : m) {
    str(k);
    str(v);
  }
}

void Out::map(const std::map<uint16_t, uint64_t>& m) {
  u32(static_cast<uint32_t>(m.size() * 10));
  for (const auto& [k, v] : m) {
    u16(k);
    u64(v);
  }
}

size_t Out::begin_record(Opcode op) {
  const size_t start = bytes_.size();
  u8(op);
  u64(0);
  return start;
}

void Out::end_record(size_t start) {
  const uint64_t length = bytes_.size() - start - kRecordPrefix;
  for (int i = 0; i < 8; ++i)
    bytes_[start + 1 + static_cast<size_t>(i)] = static_cast<uint8_t>(length >> (8 * i));
}

void In::fail(const std::string& what) const { throw BagError(where_ + ": " + what); }

void In::need(uint64_t n, const char* field) {
  if (bytes_.size() - pos_ < n) {
    fail(std::string("field '") + field + "' needs " + std::to_string(n) +
         " bytes, the record has " + std::to_string(bytes_.size() - pos_) + " left");
  }
}

uint64_t In::le(int n, const char* field) {
  need(static_cast<uint64_t>(n), field);
  uint64_t v = 0;
  for (int i = 0; i < n; ++i) v |= uint64_t{bytes_[pos_ + static_cast<size_t>(i)]} << (8 * i);
  pos_ += static_cast<size_t>(n);
  return v;
}

std::string In::str(const char* field) {
  const auto n = u32(field);
  const auto b = bytes(n, field);
  return {reinterpret_cast<const char*>(b.data()), b.size()};
}

std::span<const uint8_t> In::bytes(uint64_t n, const char* field) {
  need(n, field);
  const auto out = bytes_.subspan(pos_, static_cast<size_t>(n));
  pos_ += static_cast<size_t>(n);
  return out;
}

std::span<const uint8_t> In::rest() {
  const auto out = bytes_.subspan(pos_);
  pos_ = bytes_.size();
  return out;
}

KeyValues In::string_map(const char* field) {
  In entries(bytes(u32(field), field), where_);
  KeyValues m;
  while (entries.pos_ < entries.bytes_.size()) {
    std::string key = entries.str(field);
    m[key] = entries.str(field);
  }
  return m;
}

std::map<uint16_t, uint64_t> In::id_map(const char* field) {
  In entries(bytes(u32(field), field), where_);
  std::map<uint16_t, uint64_t> m;
  while (entries.pos_ < entries.bytes_.size()) {
    const uint16_t key = entries.u16(field);
    m[key] = entries.u64(field);
  }
  return m;
}

void put_schema(Out& out, const Schema& schema) {
  const size_t start = out.begin_record(kSchema);
  out.u16(schema.id);
  out.str(schema.name);
  out.str(schema.encoding);
  out.str(schema.data);
  out.end_record(start);
}

void put_channel(Out& out, const Channel& channel) {
  const size_t start = out.begin_record(kChannel);
  out.u16(channel.id);
  out.u16(channel.schema_id);
  out.str(channel.topic);
  out.str(channel.message_encoding);
  out.map(channel.metadata);
  out.end_record(start);
}

Schema read_schema(In& in) {
  Schema s;
  s.id = in.u16("id");
  s.name = in.str("name");
  s.encoding = in.str("encoding");
  s.data = in.str("data");
  return s;
}

Channel read_channel(In& in) {
  Channel c;
  c.id = in.u16("id");
  c.schema_id = in.u16("schema_id");
  c.topic = in.str("topic");
  c.message_encoding = in.str("message_encoding");
  c.metadata = in.string_map("metadata");
  return c;
}

Statistics read_statistics(In& in) {
  Statistics s;
  s.message_count = in.u64("message_count");
  s.schema_count = in.u16("schema_count");
  s.channel_count = in.u32("channel_count");
  s.attachment_count = in.u32("attachment_count");
  s.metadata_count = in.u32("metadata_count");
  s.chunk_count = in.u32("chunk_count");
  s.message_start_time = in.u64("message_start_time");
  s.message_end_time = in.u64("message_end_time");
  s.channel_message_counts = in.id_map("channel_message_counts");
  return s;
}

ChunkIndex read_chunk_index(In& in) {
  ChunkIndex c;
  c.message_start_time = in.u64("message_start_time");
  c.message_end_time = in.u64("message_end_time");
  c.chunk_start_offset = in.u64("chunk_start_offset");
  c.chunk_length = in.u64("chunk_length");
  c.message_index_offsets = in.id_map("message_index_offsets");
  c.message_index_length = in.u64("message_index_length");
  c.compression = in.str("compression");
  c.compressed_size = in.u64("compressed_size");
  c.uncompressed_size = in.u64("uncompressed_size");
  return c;
}

void compress(Compression compression, std::span<const uint8_t> in, std::vector<uint8_t>& out,
              void*& zstd_context) {
  switch (compression) {
    case Compression::kNone:
      out.assign(in.begin(), in.end());
      return;
    case Compression::kZstd: {
      if (zstd_context == nullptr) zstd_context = ZSTD_createCCtx();
      out.resize(ZSTD_compressBound(in.size()));
      // Level 1: the fastest of the regular levels; recording must keep up with the cameras.
      const size_t n = ZSTD_compressCCtx(static_cast<ZSTD_CCtx*>(zstd_context), out.data(),
                                         out.size(), in.data(), in.size(), 1);
      if (ZSTD_isError(n))
        throw BagError(std::string("zstd compression failed: ") + ZSTD_getErrorName(n));
      out.resize(n);
      return;
    }
    case Compression::kLz4: {
      // MCAP's "lz4" is the LZ4 frame format.
      out.resize(LZ4F_compressFrameBound(in.size(), nullptr));
      const size_t n = LZ4F_compressFrame(out.data(), out.size(), in.data(), in.size(), nullptr);
      if (LZ4F_isError(n))
        throw BagError(std::string("lz4 compression failed: ") + LZ4F_getErrorName(n));
      out.resize(n);
      return;
    }
  }
}

void free_zstd(void* zstd_context) { ZSTD_freeCCtx(static_cast<ZSTD_CCtx*>(zstd_context)); }

std::vector<uint8_t> decompress(const std::string& compression, std::span<const uint8_t> in,
                                uint64_t uncompressed_size, const std::string& where) {
  // A corrupt size field must not make the reader allocate without bound: a chunk's records
  // never expand more than this from their compressed form here.
  constexpr uint64_t kMaxRatio = 1u << 16;
  if (compression.empty()) {
    if (in.size() != uncompressed_size) {
      throw BagError(where + ": uncompressed records of " + std::to_string(in.size()) +
                     " bytes, the chunk says " + std::to_string(uncompressed_size));
    }
    return {in.begin(), in.end()};
  }
  if (uncompressed_size > (in.size() + 64) * kMaxRatio ||
      uncompressed_size > std::numeric_limits<size_t>::max() / 2) {
    throw BagError(where + ": uncompressed size " + std::to_string(uncompressed_size) +
                   " is not plausible for " + std::to_string(in.size()) + " compressed bytes");
  }
  std::vector<uint8_t> out(static_cast<size_t>(uncompressed_size));
  if (compression == "zstd") {
    const size_t n = ZSTD_decompress(out.data(), out.size(), in.data(), in.size());
    if (ZSTD_isError(n)) throw BagError(where + ": zstd: " + ZSTD_getErrorName(n));
    if (n != out.size()) {
      throw BagError(where + ": zstd gave " + std::to_string(n) + " bytes, the chunk says " +
                     std::to_string(out.size()));
    }
    return out;
  }
  if (compression == "lz4") {
    LZ4F_dctx* ctx = nullptr;
    if (LZ4F_isError(LZ4F_createDecompressionContext(&ctx, LZ4F_VERSION)))
      throw BagError(where + ": lz4: no context");
    size_t produced = 0, consumed = 0;
    size_t status = 1;
    while (status != 0 && consumed < in.size()) {
      size_t dst = out.size() - produced;
      size_t src = in.size() - consumed;
      status =
          LZ4F_decompress(ctx, out.data() + produced, &dst, in.data() + consumed, &src, nullptr);
      if (LZ4F_isError(status)) {
        LZ4F_freeDecompressionContext(ctx);
        throw BagError(where + ": lz4: " + LZ4F_getErrorName(status));
      }
      produced += dst;
      consumed += src;
      if (dst == 0 && src == 0) break;
    }
    LZ4F_freeDecompressionContext(ctx);
    if (status != 0 || produced != out.size()) {
      throw BagError(where + ": lz4 gave " + std::to_string(produced) + " bytes, the chunk says " +
                     std::to_string(out.size()));
    }
    return out;
  }
  throw BagError(where + ": unsupported compression '" + compression +
                 "' (known: zstd, lz4, none)");
}

}  // namespace concert::bag::detail

namespace concert::bag {

std::string_view to_string(Compression compression) {
  switch (compression) {
    case Compression::kNone:
      return "none";
    case Compression::kZstd:
      return "zstd";
    case Compression::kLz4:
      return "lz4";
  }
  return "?";
}

Compression parse_compression(std::string_view name) {
  if (name == "none") return Compression::kNone;
  if (name == "zstd") return Compression::kZstd;
  if (name == "lz4") return Compression::kLz4;
  throw BagError("unknown compression '" + std::string(name) + "' (known: none, zstd, lz4)");
}

}  // namespace concert::bag
