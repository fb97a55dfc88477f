#include <algorithm>
#include <cerrno>
#include <cstring>

#include "concert/bag/mcap.hpp"
#include "records.hpp"

namespace concert::bag {

using namespace detail;

Writer::Writer(const std::string& path, WriterOptions options)
    : path_(path), options_(std::move(options)) {
  file_ = std::fopen(path.c_str(), "wb");
  if (file_ == nullptr) throw BagError(path + ": cannot create: " + std::strerror(errno));
  std::vector<uint8_t> start(kMagic.begin(), kMagic.end());
  Out out(start);
  const size_t header = out.begin_record(kHeader);
  out.str(options_.profile);
  out.str(options_.library);
  out.end_record(header);
  // The data section CRC covers the magic and the header, as the reference writers do.
  put(start);
}

Writer::~Writer() {
  try {
    close();
  } catch (const BagError&) {
    // close() reports errors to callers that call it; a destructor cannot.
  }
  if (file_ != nullptr) std::fclose(file_);
  if (zstd_ != nullptr) free_zstd(zstd_);
}

void Writer::require_open(const char* what) const {
  if (file_ == nullptr) throw BagError(path_ + ": " + what + " after close()");
}

void Writer::put(std::span<const uint8_t> bytes, bool data_section) {
  if (bytes.empty()) return;
  if (std::fwrite(bytes.data(), 1, bytes.size(), file_) != bytes.size()) {
    throw BagError(path_ + ": write failed at byte " + std::to_string(position_) + ": " +
                   std::strerror(errno));
  }
  position_ += bytes.size();
  if (data_section) data_crc_ = crc32(data_crc_, bytes);
}

uint16_t Writer::add_schema(std::string name, std::string encoding, std::string data) {
  require_open("add_schema");
  if (schemas_.size() >= 0xFFFF) throw BagError(path_ + ": more than 65535 schemas");
  const auto id = static_cast<uint16_t>(schemas_.size() + 1);
  schemas_[id] = Schema{id, std::move(name), std::move(encoding), std::move(data)};
  ++statistics_.schema_count;
  return id;
}

uint16_t Writer::add_channel(uint16_t schema_id, std::string topic, std::string message_encoding,
                             KeyValues metadata) {
  require_open("add_channel");
  if (schema_id != 0 && !schemas_.count(schema_id)) {
    throw BagError(path_ + ": channel '" + topic + "' refers to schema " +
                   std::to_string(schema_id) + ", which was not added");
  }
  if (channels_.size() >= 0xFFFF) throw BagError(path_ + ": more than 65535 channels");
  const auto id = static_cast<uint16_t>(channels_.size());
  channels_[id] =
      Channel{id, schema_id, std::move(topic), std::move(message_encoding), std::move(metadata)};
  ++statistics_.channel_count;
  return id;
}

void Writer::write(const Message& message) {
  require_open("write");
  const auto channel = channels_.find(message.channel_id);
  if (channel == channels_.end()) {
    throw BagError(path_ + ": message on channel " + std::to_string(message.channel_id) +
                   ", which was not added");
  }
  Out out(chunk_);
  // A channel (and its schema) goes into the chunk of its first message, so that a reader that
  // reads the records in order knows it before any of its messages.
  if (!channels_written_.count(message.channel_id)) {
    const uint16_t schema_id = channel->second.schema_id;
    if (schema_id != 0 && !schemas_written_.count(schema_id)) {
      put_schema(out, schemas_.at(schema_id));
      schemas_written_.insert(schema_id);
    }
    put_channel(out, channel->second);
    channels_written_.insert(message.channel_id);
  }
  if (chunk_message_index_.empty()) {
    chunk_start_ = chunk_end_ = message.log_time;
  }
  chunk_message_index_[message.channel_id].emplace_back(message.log_time, chunk_.size());
  const size_t start = out.begin_record(kMessage);
  out.u16(message.channel_id);
  out.u32(message.sequence);
  out.u64(message.log_time);
  out.u64(message.publish_time);
  out.raw(message.data);
  out.end_record(start);
  chunk_start_ = std::min(chunk_start_, message.log_time);
  chunk_end_ = std::max(chunk_end_, message.log_time);

  if (statistics_.message_count == 0) {
    statistics_.message_start_time = statistics_.message_end_time = message.log_time;
  }
  statistics_.message_start_time = std::min(statistics_.message_start_time, message.log_time);
  statistics_.message_end_time = std::max(statistics_.message_end_time, message.log_time);
  ++statistics_.message_count;
  ++statistics_.channel_message_counts[message.channel_id];
  if (chunk_.size() >= options_.chunk_size) write_chunk();
}

void Writer::write_chunk() {
  if (chunk_.empty()) return;
  ChunkIndex index;
  index.message_start_time = chunk_start_;
  index.message_end_time = chunk_end_;
  index.chunk_start_offset = position_;
  index.compression = options_.compression == Compression::kNone
                          ? ""
                          : std::string(to_string(options_.compression));
  index.uncompressed_size = chunk_.size();
  const uint32_t crc = crc32(0, chunk_);
  std::span<const uint8_t> records = chunk_;
  if (options_.compression != Compression::kNone) {
    compress(options_.compression, chunk_, compressed_, zstd_);
    records = compressed_;
  }
  index.compressed_size = records.size();

  std::vector<uint8_t> head;
  Out out(head);
  out.u8(kChunk);
  out.u64(8 + 8 + 8 + 4 + 4 + index.compression.size() + 8 + records.size());
  out.u64(chunk_start_);
  out.u64(chunk_end_);
  out.u64(chunk_.size());
  out.u32(crc);
  out.str(index.compression);
  out.u64(records.size());
  put(head);
  put(records);
  index.chunk_length = position_ - index.chunk_start_offset;

  std::vector<uint8_t> indexes;
  Out idx(indexes);
  for (const auto& [channel, entries] : chunk_message_index_) {
    index.message_index_offsets[channel] = position_ + indexes.size();
    const size_t start = idx.begin_record(kMessageIndex);
    idx.u16(channel);
    idx.u32(static_cast<uint32_t>(entries.size() * 16));
    for (const auto& [time, offset] : entries) {
      idx.u64(time);
      idx.u64(offset);
    }
    idx.end_record(start);
  }
  index.message_index_length = indexes.size();
  put(indexes);
  chunk_indexes_.push_back(std::move(index));
  ++statistics_.chunk_count;
  chunk_.clear();
  chunk_message_index_.clear();
}

void Writer::add_metadata(const Metadata& metadata) {
  require_open("add_metadata");
  std::vector<uint8_t> bytes;
  Out out(bytes);
  const size_t start = out.begin_record(kMetadata);
  out.str(metadata.name);
  out.map(metadata.entries);
  out.end_record(start);
  metadata_index_.push_back({metadata.name, {position_, bytes.size()}});
  put(bytes);
  ++statistics_.metadata_count;
}

void Writer::flush() {
  require_open("flush");
  write_chunk();
  if (std::fflush(file_) != 0) throw BagError(path_ + ": flush failed: " + std::strerror(errno));
}

void Writer::close() {
  if (file_ == nullptr) return;
  write_chunk();
  std::vector<uint8_t> end;
  Out out(end);
  out.u8(kDataEnd);
  out.u64(4);
  out.u32(data_crc_);
  put(end);

  // The summary section, grouped by opcode, and one Summary Offset record per group.
  const uint64_t summary_start = position_;
  std::vector<uint8_t> summary;
  Out sum(summary);
  std::vector<std::pair<uint8_t, std::pair<uint64_t, uint64_t>>> groups;
  auto group = [&](Opcode op, const auto& write_records) {
    const size_t begin = summary.size();
    write_records();
    if (summary.size() > begin)
      groups.push_back({op, {summary_start + begin, summary.size() - begin}});
  };
  group(kSchema, [&] {
    for (const auto& [id, schema] : schemas_) put_schema(sum, schema);
  });
  group(kChannel, [&] {
    for (const auto& [id, channel] : channels_) put_channel(sum, channel);
  });
  group(kStatistics, [&] {
    const size_t start = sum.begin_record(kStatistics);
    sum.u64(statistics_.message_count);
    sum.u16(statistics_.schema_count);
    sum.u32(statistics_.channel_count);
    sum.u32(statistics_.attachment_count);
    sum.u32(statistics_.metadata_count);
    sum.u32(statistics_.chunk_count);
    sum.u64(statistics_.message_start_time);
    sum.u64(statistics_.message_end_time);
    sum.map(statistics_.channel_message_counts);
    sum.end_record(start);
  });
  group(kMetadataIndex, [&] {
    for (const auto& [name, where] : metadata_index_) {
      const size_t start = sum.begin_record(kMetadataIndex);
      sum.u64(where.first);
      sum.u64(where.second);
      sum.str(name);
      sum.end_record(start);
    }
  });
  group(kChunkIndex, [&] {
    for (const auto& c : chunk_indexes_) {
      const size_t start = sum.begin_record(kChunkIndex);
      sum.u64(c.message_start_time);
      sum.u64(c.message_end_time);
      sum.u64(c.chunk_start_offset);
      sum.u64(c.chunk_length);
      sum.map(c.message_index_offsets);
      sum.u64(c.message_index_length);
      sum.str(c.compression);
      sum.u64(c.compressed_size);
      sum.u64(c.uncompressed_size);
      sum.end_record(start);
    }
  });
  const uint64_t summary_offset_start = summary_start + summary.size();
  for (const auto& [op, where] : groups) {
    const size_t start = sum.begin_record(kSummaryOffset);
    sum.u8(op);
    sum.u64(where.first);
    sum.u64(where.second);
    sum.end_record(start);
  }
  sum.u8(kFooter);
  sum.u64(8 + 8 + 4);
  sum.u64(summary_start);
  sum.u64(summary_offset_start);
  sum.u32(crc32(0, summary));
  sum.raw(kMagic);
  put(summary, false);

  std::FILE* file = file_;
  file_ = nullptr;
  if (std::fclose(file) != 0) throw BagError(path_ + ": closing failed: " + std::strerror(errno));
}

}  // namespace concert::bag
