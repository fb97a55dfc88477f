#include <algorithm>
#include <cerrno>
#include <cstring>

#include "concert/bag/mcap.hpp"
#include "records.hpp"

namespace concert::bag {

using namespace detail;

namespace {

std::string at_byte(uint64_t offset) { return "byte " + std::to_string(offset); }

/// Keeps a Schema or Channel record; false for other records.
bool take_definition(uint8_t op, In& in, std::map<uint16_t, Schema>& schemas,
                     std::map<uint16_t, Channel>& channels) {
  if (op == kSchema) {
    auto schema = read_schema(in);
    schemas[schema.id] = std::move(schema);
    return true;
  }
  if (op == kChannel) {
    auto channel = read_channel(in);
    channels[channel.id] = std::move(channel);
    return true;
  }
  return false;
}

}  // namespace

/// State of one pass over the data section.
struct Reader::Scan {
  std::map<uint16_t, Schema> schemas;
  std::map<uint16_t, Channel> channels;
  Statistics statistics;
  std::vector<Metadata> metadata;
  std::set<std::string> compressions;
  std::function<bool(const Message&, const Channel&)> on_message;  // may be empty
  bool stopped = false;                                            // on_message returned false
};

Reader::Reader(const std::string& path) : path_(path) {
  file_ = std::fopen(path.c_str(), "rb");
  if (file_ == nullptr) throw BagError(path + ": cannot open: " + std::strerror(errno));
  try {
    open_header();
  } catch (...) {
    // A constructor that throws runs no destructor: the file would stay open.
    std::fclose(file_);
    file_ = nullptr;
    throw;
  }
}

void Reader::open_header() {
  const std::string& path = path_;
  std::fseek(file_, 0, SEEK_END);
  size_ = static_cast<uint64_t>(std::ftell(file_));
  std::fseek(file_, 0, SEEK_SET);
  std::array<uint8_t, 8 + kRecordPrefix> start{};
  const size_t got = std::fread(start.data(), 1, start.size(), file_);
  if (got < kMagic.size() || !std::equal(kMagic.begin(), kMagic.end(), start.begin())) {
    throw BagError(path + ": not an MCAP file (it does not start with the MCAP magic bytes)");
  }
  if (got < start.size() || start[8] != kHeader) {
    throw BagError(path + ": no Header record after the magic bytes (" +
                   (got < start.size() ? std::string("the file ends there")
                                       : record_name(start[8]) + " instead") +
                   ")");
  }
  uint64_t length = 0;
  for (int i = 0; i < 8; ++i) length |= uint64_t{start[9 + static_cast<size_t>(i)]} << (8 * i);
  if (length > size_ - start.size())
    throw BagError(path + ": the file ends inside its Header record");
  std::vector<uint8_t> header(static_cast<size_t>(length));
  if (std::fread(header.data(), 1, header.size(), file_) != header.size()) {
    throw BagError(path + ": cannot read the Header record");
  }
  In in(header, path + ": Header record at byte 8");
  profile_ = in.str("profile");
  library_ = in.str("library");
  data_start_ = start.size() + length;
  complete_ = read_summary_section();
}

Reader::~Reader() {
  if (file_ != nullptr) std::fclose(file_);
}

bool Reader::read_summary_section() {
  if (size_ < data_start_ + kFooterSize + kMagic.size()) {
    problem_ =
        "no footer (the file is " + std::to_string(size_) + " bytes: the recording was cut short)";
    return false;
  }
  std::array<uint8_t, kFooterSize + 8> tail{};
  std::fseek(file_, static_cast<long>(size_ - tail.size()), SEEK_SET);
  if (std::fread(tail.data(), 1, tail.size(), file_) != tail.size())
    throw BagError(path_ + ": cannot read its end");
  if (!std::equal(kMagic.begin(), kMagic.end(), tail.begin() + kFooterSize) || tail[0] != kFooter) {
    problem_ =
        "no footer and closing magic bytes at its end (the recording was cut short, or the file "
        "was not closed)";
    return false;
  }
  const uint64_t footer_start = size_ - tail.size();
  In footer(std::span<const uint8_t>(tail).subspan(1, kFooterSize - 1),
            path_ + ": Footer at " + at_byte(footer_start));
  if (footer.u64("length") != 20) footer.fail("length is not 20");
  const uint64_t summary_start = footer.u64("summary_start");
  const uint64_t summary_offset_start = footer.u64("summary_offset_start");
  const uint32_t summary_crc = footer.u32("summary_crc");
  if (summary_start == 0) return true;  // complete, without summary: summary() scans
  if (summary_start < data_start_ || summary_start > footer_start ||
      (summary_offset_start != 0 &&
       (summary_offset_start < summary_start || summary_offset_start > footer_start))) {
    throw BagError(path_ + ": Footer at " + at_byte(footer_start) + ": summary offsets " +
                   std::to_string(summary_start) + "/" + std::to_string(summary_offset_start) +
                   " lie outside the file's summary");
  }
  // The summary CRC covers the summary and summary offset sections and the footer's fields
  // before the CRC.
  std::vector<uint8_t> bytes(static_cast<size_t>(footer_start + kFooterSize - 4 - summary_start));
  std::fseek(file_, static_cast<long>(summary_start), SEEK_SET);
  if (std::fread(bytes.data(), 1, bytes.size(), file_) != bytes.size())
    throw BagError(path_ + ": cannot read its summary");
  if (summary_crc != 0 && crc32(0, bytes) != summary_crc) {
    throw BagError(path_ +
                   ": the summary section's CRC does not match (the file is corrupt after " +
                   at_byte(summary_start) + ")");
  }
  Summary summary;
  summary.profile = profile_;
  summary.library = library_;
  summary.file_size = size_;
  summary.from_summary_section = true;
  const uint64_t end =
      (summary_offset_start != 0 ? summary_offset_start : footer_start) - summary_start;
  std::vector<std::pair<uint64_t, uint64_t>> metadata_at;
  for (uint64_t pos = 0; pos < end;) {
    const std::string where = path_ + ": summary " + at_byte(summary_start + pos);
    In prefix(std::span<const uint8_t>(bytes).subspan(static_cast<size_t>(pos)), where);
    const uint8_t op = prefix.u8("opcode");
    const uint64_t length = prefix.u64("length");
    if (length > end - pos - kRecordPrefix)
      throw BagError(where + ": " + record_name(op) + " record overruns the summary");
    In in(std::span<const uint8_t>(bytes).subspan(static_cast<size_t>(pos + kRecordPrefix),
                                                  static_cast<size_t>(length)),
          where + " (" + record_name(op) + ")");
    if (take_definition(op, in, summary.schemas, summary.channels)) {
      pos += kRecordPrefix + length;
      continue;
    }
    switch (op) {
      case kStatistics:
        summary.statistics = read_statistics(in);
        break;
      case kChunkIndex: {
        auto c = read_chunk_index(in);
        summary.compressions.insert(c.compression);
        summary.chunk_indexes.push_back(std::move(c));
        break;
      }
      case kMetadataIndex: {
        const uint64_t offset = in.u64("offset");
        const uint64_t len = in.u64("length");
        metadata_at.emplace_back(offset, len);
        break;
      }
      default:
        break;  // attachment indexes and records of later versions
    }
    pos += kRecordPrefix + length;
  }
  for (const auto& [offset, length] : metadata_at) {
    const std::string where = path_ + ": Metadata record at " + at_byte(offset);
    if (length < kRecordPrefix || offset > size_ || length > size_ - offset)
      throw BagError(where + ": outside the file");
    std::vector<uint8_t> record(static_cast<size_t>(length));
    std::fseek(file_, static_cast<long>(offset), SEEK_SET);
    if (std::fread(record.data(), 1, record.size(), file_) != record.size())
      throw BagError(where + ": cannot read it");
    if (record[0] != kMetadata)
      throw BagError(where + ": the index points at a " + record_name(record[0]) + " record");
    In in(std::span<const uint8_t>(record).subspan(kRecordPrefix), where);
    Metadata m;
    m.name = in.str("name");
    m.entries = in.string_map("metadata");
    summary.metadata.push_back(std::move(m));
  }
  summary_ = std::move(summary);
  return true;
}

const Summary& Reader::summary() {
  if (summary_) return *summary_;
  Scan s;
  scan(s);
  Summary summary;
  summary.profile = profile_;
  summary.library = library_;
  summary.file_size = size_;
  summary.schemas = std::move(s.schemas);
  summary.channels = std::move(s.channels);
  summary.statistics = std::move(s.statistics);
  summary.statistics.schema_count = static_cast<uint16_t>(summary.schemas.size());
  summary.statistics.channel_count = static_cast<uint32_t>(summary.channels.size());
  summary.metadata = std::move(s.metadata);
  summary.compressions = std::move(s.compressions);
  summary_ = std::move(summary);
  return *summary_;
}

void Reader::read_messages(const std::function<bool(const Message&, const Channel&)>& on_message) {
  Scan s;
  s.on_message = on_message;
  scan(s);
}

void Reader::scan(Scan& s) {
  // The data section CRC covers everything from the magic up to the Data End record.
  std::vector<uint8_t> head(static_cast<size_t>(data_start_));
  std::fseek(file_, 0, SEEK_SET);
  if (std::fread(head.data(), 1, head.size(), file_) != head.size())
    throw BagError(path_ + ": cannot read its header");
  uint32_t crc = crc32(0, head);

  auto on_record = [&](uint8_t op, In& in) {
    if (take_definition(op, in, s.schemas, s.channels)) return;
    switch (op) {
      case kMessage: {
        Message m;
        m.channel_id = in.u16("channel_id");
        m.sequence = in.u32("sequence");
        m.log_time = in.u64("log_time");
        m.publish_time = in.u64("publish_time");
        m.data = in.rest();
        const auto channel = s.channels.find(m.channel_id);
        if (channel == s.channels.end()) {
          in.fail("message on channel " + std::to_string(m.channel_id) +
                  ", which no Channel record before it defines");
        }
        auto& st = s.statistics;
        if (st.message_count == 0) st.message_start_time = st.message_end_time = m.log_time;
        st.message_start_time = std::min(st.message_start_time, m.log_time);
        st.message_end_time = std::max(st.message_end_time, m.log_time);
        ++st.message_count;
        ++st.channel_message_counts[m.channel_id];
        if (s.on_message && !s.on_message(m, channel->second)) s.stopped = true;
        return;
      }
      default:
        return;  // message indexes, records of later versions and of applications
    }
  };

  std::vector<uint8_t> record;
  uint64_t pos = data_start_;
  std::fseek(file_, static_cast<long>(pos), SEEK_SET);
  const std::string cut = " (the recording was cut short): read up to there";
  while (!s.stopped) {
    if (pos == size_) {
      problem_ = "the file ends after the record before " + at_byte(pos) +
                 " without a Data End record" + cut;
      return;
    }
    std::array<uint8_t, kRecordPrefix> prefix{};
    const size_t got = std::fread(prefix.data(), 1, prefix.size(), file_);
    const uint8_t op = prefix[0];
    if (op == 0 || (op > kDataEnd && op < 0x80)) {
      problem_ = "no record at " + at_byte(pos) + " (" +
                 (op == 0 ? std::string("zero bytes") : record_name(op)) + ")" + cut;
      return;
    }
    uint64_t length = 0;
    for (int i = 0; i < 8; ++i) length |= uint64_t{prefix[1 + static_cast<size_t>(i)]} << (8 * i);
    if (got < prefix.size() || length > size_ - pos - kRecordPrefix) {
      problem_ = "the file ends inside a " + record_name(op) + " record that starts at " +
                 at_byte(pos) + cut;
      return;
    }
    record.resize(static_cast<size_t>(length));
    if (std::fread(record.data(), 1, record.size(), file_) != record.size()) {
      throw BagError(path_ + ": cannot read the record at " + at_byte(pos));
    }
    const std::string where = path_ + ": " + record_name(op) + " record at " + at_byte(pos);
    In in(record, where);
    if (op == kDataEnd) {
      const uint32_t expected = in.u32("data_section_crc");
      if (expected != 0 && expected != crc) {
        throw BagError(where +
                       ": the data section's CRC does not match (the file is corrupt before " +
                       at_byte(pos) + ")");
      }
      return;
    }
    crc = crc32(crc, prefix);
    crc = crc32(crc, record);
    if (op == kChunk) {
      ChunkIndex c;
      c.message_start_time = in.u64("message_start_time");
      c.message_end_time = in.u64("message_end_time");
      c.uncompressed_size = in.u64("uncompressed_size");
      const uint32_t records_crc = in.u32("uncompressed_crc");
      c.compression = in.str("compression");
      const auto records = decompress(c.compression, in.bytes(in.u64("records length"), "records"),
                                      c.uncompressed_size, where);
      if (records_crc != 0 && crc32(0, records) != records_crc) {
        throw BagError(where + ": the CRC of its records does not match (the chunk is corrupt)");
      }
      s.compressions.insert(c.compression);
      ++s.statistics.chunk_count;
      for (uint64_t at = 0; at < records.size() && !s.stopped;) {
        const std::string inner =
            where + ", record at offset " + std::to_string(at) + " of its records";
        In p(std::span<const uint8_t>(records).subspan(static_cast<size_t>(at)), inner);
        const uint8_t inner_op = p.u8("opcode");
        const uint64_t inner_length = p.u64("length");
        if (inner_length > records.size() - at - kRecordPrefix)
          p.fail(record_name(inner_op) + " record overruns the chunk");
        In content(std::span<const uint8_t>(records).subspan(
                       static_cast<size_t>(at + kRecordPrefix), static_cast<size_t>(inner_length)),
                   inner + " (" + record_name(inner_op) + ")");
        on_record(inner_op, content);
        at += kRecordPrefix + inner_length;
      }
    } else if (op == kMetadata) {
      Metadata m;
      m.name = in.str("name");
      m.entries = in.string_map("metadata");
      s.metadata.push_back(std::move(m));
      ++s.statistics.metadata_count;
    } else if (op == kAttachment) {
      ++s.statistics.attachment_count;
    } else {
      on_record(op, in);
    }
    pos += kRecordPrefix + length;
  }
}

}  // namespace concert::bag
