#pragma once
// MCAP files (the format of https://mcap.dev/spec, major version 0): a writer that records as it
// goes, in chunks, and closes the file with a summary section (schemas, channels, statistics,
// chunk and metadata indexes, summary offsets), and a reader that reads the summary of a
// complete file or, for a file cut short (a crash mid-recording), every record up to the last
// complete one and says where the file ends. No DDS here: the recorder and player of
// `concert bag` put DDS samples in and take them out.
//
// Hand-written: Debian 12 packages no MCAP library (the reference C++ library is a header-only
// download), and the format is small (15 record kinds of fixed fields). Independent readers
// check what this writes (tools/mcap_check, @mcap/core). CRCs: zlib's crc32; chunk compression:
// libzstd or liblz4's frame format, both Debian packages.

#include <cstdint>
#include <cstdio>
#include <functional>
#include <map>
#include <optional>
#include <set>
#include <span>
#include <stdexcept>
#include <string>
#include <string_view>
#include <vector>

namespace concert::bag {

/// A file that cannot be written or read; the message names the file, the byte offset and
/// the record where that applies, and what is wrong.
class BagError : public std::runtime_error {
 public:
  using std::runtime_error::runtime_error;
};

/// How chunks are compressed.
enum class Compression { kNone, kZstd, kLz4 };

/// "none", "zstd" or "lz4".
std::string_view to_string(Compression compression);
/// Parses "none", "zstd" or "lz4"; throws BagError naming the known ones otherwise.
Compression parse_compression(std::string_view name);

using KeyValues = std::map<std::string, std::string>;

struct Schema {
  uint16_t id = 0;       ///< 1.. (0 means "no schema" in MCAP)
  std::string name;      ///< e.g. "concert::msg::JointState"
  std::string encoding;  ///< e.g. "omgidl"
  std::string data;      ///< e.g. the IDL text
};

struct Channel {
  uint16_t id = 0;
  uint16_t schema_id = 0;
  std::string topic;
  std::string message_encoding;  ///< e.g. "cdr"
  KeyValues metadata;
};

/// One message; `data` is only valid during the call it is handed to.
struct Message {
  uint16_t channel_id = 0;
  uint32_t sequence = 0;
  uint64_t log_time = 0;      ///< [ns] when it was recorded
  uint64_t publish_time = 0;  ///< [ns] when it was published (log_time if unknown)
  std::span<const uint8_t> data;
};

struct Metadata {
  std::string name;
  KeyValues entries;
};

/// The Statistics record of a file.
struct Statistics {
  uint64_t message_count = 0;
  uint16_t schema_count = 0;
  uint32_t channel_count = 0;
  uint32_t attachment_count = 0;
  uint32_t metadata_count = 0;
  uint32_t chunk_count = 0;
  uint64_t message_start_time = 0;  ///< [ns] earliest log_time (0 without messages)
  uint64_t message_end_time = 0;    ///< [ns] latest log_time
  std::map<uint16_t, uint64_t> channel_message_counts;
};

struct ChunkIndex {
  uint64_t message_start_time = 0;
  uint64_t message_end_time = 0;
  uint64_t chunk_start_offset = 0;  ///< [byte] of the Chunk record
  uint64_t chunk_length = 0;        ///< [byte] the Chunk record, opcode and length included
  std::map<uint16_t, uint64_t> message_index_offsets;
  uint64_t message_index_length = 0;
  std::string compression;  ///< "", "zstd" or "lz4" as in the file
  uint64_t compressed_size = 0;
  uint64_t uncompressed_size = 0;
};

struct WriterOptions {
  Compression compression = Compression::kZstd;
  /// A chunk is written once its records reach this many bytes (uncompressed).
  uint64_t chunk_size = 1 << 20;
  std::string profile;  ///< Header.profile ("" : none of the well-known profiles)
  std::string library = "concert libs/bag";
};

/// Writes an MCAP file as it goes: messages are gathered in a chunk in memory, which is
/// compressed and written when it reaches `chunk_size` or on flush(); close() (or the
/// destructor) writes the summary section and the footer. Memory stays bounded by one chunk
/// plus the summary (one chunk index per chunk). Not thread-safe: one thread writes.
class Writer {
 public:
  /// Creates (or truncates) `path` and writes the magic and the Header.
  Writer(const std::string& path, WriterOptions options = {});
  /// close(), errors ignored (call close() to see them).
  ~Writer();
  Writer(const Writer&) = delete;
  Writer& operator=(const Writer&) = delete;

  /// Registers a schema; written into the file before the first message that needs it.
  uint16_t add_schema(std::string name, std::string encoding, std::string data);
  /// Registers a channel of schema `schema_id` (0: none).
  uint16_t add_channel(uint16_t schema_id, std::string topic, std::string message_encoding,
                       KeyValues metadata = {});
  /// Adds a message on a registered channel.
  void write(const Message& message);
  /// Adds a Metadata record (written at once, outside chunks).
  void add_metadata(const Metadata& metadata);
  /// Writes the open chunk (if any) and hands the file's buffers to the OS, so that a crash
  /// from now on loses nothing written so far.
  void flush();
  /// Writes the open chunk, the Data End record, the summary and the footer, and closes the
  /// file. Nothing may be written after.
  void close();

  const Statistics& statistics() const { return statistics_; }
  /// Bytes in the file so far (not counting the open chunk).
  uint64_t file_size() const { return position_; }
  /// Uncompressed bytes of the open chunk.
  uint64_t pending_bytes() const { return chunk_.size(); }
  const std::string& path() const { return path_; }

 private:
  void put(std::span<const uint8_t> bytes, bool data_section = true);
  void write_chunk();
  void require_open(const char* what) const;

  std::string path_;
  WriterOptions options_;
  std::FILE* file_ = nullptr;
  uint64_t position_ = 0;
  uint32_t data_crc_ = 0;
  std::map<uint16_t, Schema> schemas_;
  std::map<uint16_t, Channel> channels_;
  std::set<uint16_t> schemas_written_, channels_written_;
  std::vector<ChunkIndex> chunk_indexes_;
  std::vector<std::pair<std::string, std::pair<uint64_t, uint64_t>>> metadata_index_;
  Statistics statistics_;
  // The open chunk: its records, message time range and message index per channel.
  std::vector<uint8_t> chunk_;
  uint64_t chunk_start_ = 0, chunk_end_ = 0;
  std::map<uint16_t, std::vector<std::pair<uint64_t, uint64_t>>> chunk_message_index_;
  std::vector<uint8_t> compressed_;
  void* zstd_ = nullptr;  // ZSTD_CCtx, reused across chunks
};

/// What a file holds, from its summary section or, for a file without one, from reading every
/// record.
struct Summary {
  std::string profile, library;
  std::map<uint16_t, Schema> schemas;
  std::map<uint16_t, Channel> channels;
  Statistics statistics;
  std::vector<ChunkIndex> chunk_indexes;  ///< empty when read by scanning
  std::vector<Metadata> metadata;
  std::set<std::string> compressions;  ///< of the chunks ("" = none)
  uint64_t file_size = 0;
  bool from_summary_section = false;  ///< false: gathered by reading every record
};

/// Reads an MCAP file. A complete file (footer, summary, closing magic) is summarised from its
/// summary section; one cut short is read record by record up to its last complete record, and
/// problem() says where and why it ends. CRCs (chunks, data section, summary) are checked.
class Reader {
 public:
  /// Opens `path`, checks the magic and reads the Header; throws BagError otherwise.
  explicit Reader(const std::string& path);
  ~Reader();
  Reader(const Reader&) = delete;
  Reader& operator=(const Reader&) = delete;

  /// True if the file ends with a valid footer, summary section and magic.
  bool complete() const { return complete_; }
  /// Why the file is not complete, e.g. "file ends inside a Chunk record at byte 1234 (the
  /// recording was cut short): read up to byte 1200"; empty for a complete file. Set by the
  /// constructor for a missing footer, and by read_messages()/summary() for where the records
  /// stop.
  const std::string& problem() const { return problem_; }

  /// The file's summary (the summary section, or else a full read of the records).
  const Summary& summary();

  /// Calls `on_message` for every message in file order (for this writer: log_time order) until
  /// it returns false. Channels and schemas come from the records before each message. Stops
  /// at the Data End record or, in a file cut short, at the last complete record (problem()
  /// then says so). Throws BagError for a corrupt record (CRC mismatch, fields that do not fit
  /// their record, a message on an unknown channel).
  void read_messages(const std::function<bool(const Message&, const Channel&)>& on_message);

  const std::string& path() const { return path_; }

 private:
  struct Scan;
  void open_header();  // the constructor's reading of the magic and the Header
  bool read_summary_section();
  void scan(Scan& scan);

  std::string path_;
  std::FILE* file_ = nullptr;
  uint64_t size_ = 0;
  uint64_t data_start_ = 0;  // first record after the Header
  bool complete_ = false;
  std::string problem_;
  std::optional<Summary> summary_;
  std::string profile_, library_;
};

}  // namespace concert::bag
