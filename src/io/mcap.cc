#include "rotorguard/io/mcap.h"

#include <array>
#include <cstring>
#include <limits>

#include <fmt/format.h>

#include "rotorguard/core/error.h"
#include "rotorguard/io/config_node.h"

namespace rotorguard::io {

namespace {

constexpr std::string_view kMagic("\x89MCAP0\r\n", 8);

// Record opcodes (spec, "Records").
enum Opcode : std::uint8_t {
  kHeader = 0x01,
  kFooter = 0x02,
  kSchema = 0x03,
  kChannel = 0x04,
  kMessage = 0x05,
  kChunk = 0x06,
  kMessageIndex = 0x07,
  kChunkIndex = 0x08,
  kStatistics = 0x0B,
  kMetadata = 0x0C,
  kMetadataIndex = 0x0D,
  kSummaryOffset = 0x0E,
  kDataEnd = 0x0F,
};

// ---- Little-endian primitives (spec, "Serialization").

template <typename T>
void Put(std::string* out, T v) {
  for (std::size_t i = 0; i < sizeof(T); ++i) out->push_back(static_cast<char>((static_cast<std::uint64_t>(v) >> (8 * i)) & 0xFF));
}
void PutString(std::string* out, std::string_view s) {
  Put<std::uint32_t>(out, static_cast<std::uint32_t>(s.size()));
  out->append(s);
}
void PutStringMap(std::string* out, const std::map<std::string, std::string>& m) {
  std::string body;
  for (const auto& [k, v] : m) PutString(&body, k), PutString(&body, v);
  Put<std::uint32_t>(out, static_cast<std::uint32_t>(body.size()));
  out->append(body);
}
/// Appends a record (opcode, length, body) and returns the offset where it starts.
std::uint64_t PutRecord(std::string* out, std::uint8_t opcode, std::string_view body) {
  const std::uint64_t at = out->size();
  Put<std::uint8_t>(out, opcode);
  Put<std::uint64_t>(out, body.size());
  out->append(body);
  return at;
}

std::array<std::uint32_t, 256> MakeCrcTable() {
  std::array<std::uint32_t, 256> table{};
  for (std::uint32_t i = 0; i < 256; ++i) {
    std::uint32_t c = i;
    for (int k = 0; k < 8; ++k) c = (c & 1u) ? 0xEDB88320u ^ (c >> 1) : c >> 1;
    table[i] = c;
  }
  return table;
}

}  // namespace

std::uint32_t Crc32(std::string_view data, std::uint32_t crc) {
  static const std::array<std::uint32_t, 256> table = MakeCrcTable();
  crc = ~crc;
  for (const char ch : data) crc = table[(crc ^ static_cast<std::uint8_t>(ch)) & 0xFFu] ^ (crc >> 8);
  return ~crc;
}

std::string Base64Encode(std::string_view bytes) {
  static constexpr char kAlphabet[] = "ABCDEFGHIJKLMNOPQRSTUVWXYZabcdefghijklmnopqrstuvwxyz0123456789+/";
  std::string out;
  out.reserve((bytes.size() + 2) / 3 * 4);
  std::size_t i = 0;
  for (; i + 3 <= bytes.size(); i += 3) {
    const std::uint32_t v = (static_cast<std::uint8_t>(bytes[i]) << 16) | (static_cast<std::uint8_t>(bytes[i + 1]) << 8) |
                            static_cast<std::uint8_t>(bytes[i + 2]);
    for (int k = 3; k >= 0; --k) out.push_back(kAlphabet[(v >> (6 * k)) & 0x3F]);
  }
  const std::size_t rest = bytes.size() - i;
  if (rest > 0) {
    std::uint32_t v = static_cast<std::uint8_t>(bytes[i]) << 16;
    if (rest == 2) v |= static_cast<std::uint8_t>(bytes[i + 1]) << 8;
    out.push_back(kAlphabet[(v >> 18) & 0x3F]);
    out.push_back(kAlphabet[(v >> 12) & 0x3F]);
    out.push_back(rest == 2 ? kAlphabet[(v >> 6) & 0x3F] : '=');
    out.push_back('=');
  }
  return out;
}

// ---- Writer.

McapWriter::McapWriter(const McapWriterOptions& options) : options_(options) {
  if (options_.chunk_size == 0) ThrowInvalidArgument("McapWriter", "chunk_size", options_.chunk_size, "> 0");
  out_.append(kMagic);
  std::string body;
  PutString(&body, options_.profile);
  PutString(&body, options_.library);
  PutRecord(&out_, kHeader, body);
}

std::uint16_t McapWriter::AddSchema(std::string_view name, std::string_view encoding, std::string_view data) {
  RG_INVARIANT(!finished_, "McapWriter used after Finish");
  const auto id = static_cast<std::uint16_t>(schemas_count_ + 1);
  ++schemas_count_;
  std::string body;
  Put<std::uint16_t>(&body, id);
  PutString(&body, name);
  PutString(&body, encoding);
  PutString(&body, data);  // bytes with a uint32 length, laid out as a string
  PutRecord(&out_, kSchema, body);
  PutRecord(&schemas_, kSchema, body);
  return id;
}

std::uint16_t McapWriter::AddChannel(std::uint16_t schema_id, std::string_view topic, std::string_view message_encoding,
                                     const std::map<std::string, std::string>& metadata) {
  RG_INVARIANT(!finished_, "McapWriter used after Finish");
  if (schema_id == 0 || schema_id > schemas_count_) {
    ThrowInvalidArgument("McapWriter::AddChannel", "schema_id", schema_id, "an id returned by AddSchema");
  }
  const auto id = static_cast<std::uint16_t>(sequence_.size());
  sequence_.push_back(0);
  std::string body;
  Put<std::uint16_t>(&body, id);
  Put<std::uint16_t>(&body, schema_id);
  PutString(&body, topic);
  PutString(&body, message_encoding);
  PutStringMap(&body, metadata);
  PutRecord(&out_, kChannel, body);
  PutRecord(&channels_, kChannel, body);
  return id;
}

void McapWriter::AddMessage(std::uint16_t channel_id, std::uint64_t log_time_ns, std::string_view data) {
  RG_INVARIANT(!finished_, "McapWriter used after Finish");
  if (channel_id >= sequence_.size()) {
    ThrowInvalidArgument("McapWriter::AddMessage", "channel_id", channel_id, "an id returned by AddChannel");
  }
  std::string body;
  Put<std::uint16_t>(&body, channel_id);
  Put<std::uint32_t>(&body, sequence_[channel_id]++);
  Put<std::uint64_t>(&body, log_time_ns);
  Put<std::uint64_t>(&body, log_time_ns);  // publish time: the same instant in a simulation
  body.append(data);
  if (chunk_.empty()) chunk_start_ns_ = chunk_end_ns_ = log_time_ns;
  chunk_start_ns_ = std::min(chunk_start_ns_, log_time_ns);
  chunk_end_ns_ = std::max(chunk_end_ns_, log_time_ns);
  chunk_index_[channel_id].emplace_back(log_time_ns, PutRecord(&chunk_, kMessage, body));
  if (message_count_ == 0) start_ns_ = end_ns_ = log_time_ns;
  start_ns_ = std::min(start_ns_, log_time_ns);
  end_ns_ = std::max(end_ns_, log_time_ns);
  ++message_count_;
  ++channel_counts_[channel_id];
  if (chunk_.size() >= options_.chunk_size) CloseChunk();
}

void McapWriter::AddMetadata(std::string_view name, const std::map<std::string, std::string>& metadata) {
  RG_INVARIANT(!finished_, "McapWriter used after Finish");
  CloseChunk();  // keeps the file in time order: the metadata after the messages before it
  std::string body;
  PutString(&body, name);
  PutStringMap(&body, metadata);
  const std::uint64_t at = PutRecord(&out_, kMetadata, body);
  std::string index;
  Put<std::uint64_t>(&index, at);
  Put<std::uint64_t>(&index, out_.size() - at);
  PutString(&index, name);
  PutRecord(&metadata_indexes_, kMetadataIndex, index);
  ++metadata_count_;
}

void McapWriter::CloseChunk() {
  if (chunk_.empty()) return;
  std::string body;
  Put<std::uint64_t>(&body, chunk_start_ns_);
  Put<std::uint64_t>(&body, chunk_end_ns_);
  Put<std::uint64_t>(&body, chunk_.size());
  Put<std::uint32_t>(&body, Crc32(chunk_));
  PutString(&body, "");  // no compression
  Put<std::uint64_t>(&body, chunk_.size());
  body.append(chunk_);
  const std::uint64_t chunk_start = PutRecord(&out_, kChunk, body);
  const std::uint64_t chunk_length = out_.size() - chunk_start;
  // One message index per channel, right after its chunk; the chunk index points at them.
  std::string offsets;
  const std::uint64_t indexes_start = out_.size();
  for (const auto& [channel, entries] : chunk_index_) {
    std::string index;
    Put<std::uint16_t>(&index, channel);
    Put<std::uint32_t>(&index, static_cast<std::uint32_t>(entries.size() * 16));
    for (const auto& [time, offset] : entries) Put<std::uint64_t>(&index, time), Put<std::uint64_t>(&index, offset);
    Put<std::uint16_t>(&offsets, channel);
    Put<std::uint64_t>(&offsets, PutRecord(&out_, kMessageIndex, index));
  }
  std::string ci;
  Put<std::uint64_t>(&ci, chunk_start_ns_);
  Put<std::uint64_t>(&ci, chunk_end_ns_);
  Put<std::uint64_t>(&ci, chunk_start);
  Put<std::uint64_t>(&ci, chunk_length);
  Put<std::uint32_t>(&ci, static_cast<std::uint32_t>(offsets.size()));
  ci.append(offsets);
  Put<std::uint64_t>(&ci, out_.size() - indexes_start);
  PutString(&ci, "");
  Put<std::uint64_t>(&ci, chunk_.size());  // compressed size: uncompressed
  Put<std::uint64_t>(&ci, chunk_.size());
  PutRecord(&chunk_indexes_, kChunkIndex, ci);
  ++chunk_count_;
  chunk_.clear();
  chunk_index_.clear();
}

std::string McapWriter::Finish() {
  RG_INVARIANT(!finished_, "McapWriter::Finish called twice");
  CloseChunk();
  finished_ = true;
  std::string data_end;
  Put<std::uint32_t>(&data_end, Crc32(out_));
  PutRecord(&out_, kDataEnd, data_end);

  // Summary section: one group per record kind, each located by a summary offset record.
  const std::uint64_t summary_start = out_.size();
  std::string groups;
  const auto group = [&](std::uint8_t opcode, const std::string& records) {
    if (records.empty()) return;
    std::string offset;
    Put<std::uint8_t>(&offset, opcode);
    Put<std::uint64_t>(&offset, out_.size());
    Put<std::uint64_t>(&offset, records.size());
    PutRecord(&groups, kSummaryOffset, offset);
    out_.append(records);
  };
  std::string statistics;
  {
    std::string body;
    Put<std::uint64_t>(&body, message_count_);
    Put<std::uint16_t>(&body, static_cast<std::uint16_t>(schemas_count_));
    Put<std::uint32_t>(&body, static_cast<std::uint32_t>(sequence_.size()));
    Put<std::uint32_t>(&body, 0);  // attachments
    Put<std::uint32_t>(&body, metadata_count_);
    Put<std::uint32_t>(&body, chunk_count_);
    Put<std::uint64_t>(&body, start_ns_);
    Put<std::uint64_t>(&body, end_ns_);
    std::string counts;
    for (const auto& [channel, count] : channel_counts_) Put<std::uint16_t>(&counts, channel), Put<std::uint64_t>(&counts, count);
    Put<std::uint32_t>(&body, static_cast<std::uint32_t>(counts.size()));
    body.append(counts);
    PutRecord(&statistics, kStatistics, body);
  }
  group(kSchema, schemas_);
  group(kChannel, channels_);
  group(kStatistics, statistics);
  group(kChunkIndex, chunk_indexes_);
  group(kMetadataIndex, metadata_indexes_);
  const std::uint64_t summary_offset_start = out_.size();
  out_.append(groups);

  std::string footer;
  Put<std::uint64_t>(&footer, summary_start);
  Put<std::uint64_t>(&footer, summary_offset_start);
  // The summary CRC covers the summary, the summary offsets and the footer up to this field.
  std::string footer_prefix;
  Put<std::uint8_t>(&footer_prefix, kFooter);
  Put<std::uint64_t>(&footer_prefix, 20);
  footer_prefix.append(footer);
  const std::uint32_t crc =
      Crc32(footer_prefix, Crc32(std::string_view(out_).substr(summary_start)));
  Put<std::uint32_t>(&footer, crc);
  PutRecord(&out_, kFooter, footer);
  out_.append(kMagic);
  return std::move(out_);
}

// ---- Reader.

namespace {

/// A bounds-checked little-endian cursor over part of the file; `base` is its offset in the file.
class Cursor {
 public:
  Cursor(std::string_view bytes, std::uint64_t base, const std::string* path) : b_(bytes), base_(base), path_(path) {}
  bool done() const { return pos_ >= b_.size(); }
  std::uint64_t offset() const { return base_ + pos_; }
  std::size_t remaining() const { return b_.size() - pos_; }
  template <typename T>
  T Get(const char* what) {
    Need(sizeof(T), what);
    std::uint64_t v = 0;
    for (std::size_t i = 0; i < sizeof(T); ++i) {
      v |= static_cast<std::uint64_t>(static_cast<std::uint8_t>(b_[pos_ + i])) << (8 * i);
    }
    pos_ += sizeof(T);
    return static_cast<T>(v);
  }
  std::string_view Bytes(std::uint64_t n, const char* what) {
    Need(n, what);
    const std::string_view s = b_.substr(pos_, n);
    pos_ += n;
    return s;
  }
  std::string String(const char* what) { return std::string(Bytes(Get<std::uint32_t>(what), what)); }
  std::map<std::string, std::string> StringMap(const char* what) {
    const std::uint32_t n = Get<std::uint32_t>(what);
    const std::uint64_t at = offset();
    Cursor inner(Bytes(n, what), at, path_);
    std::map<std::string, std::string> m;
    while (!inner.done()) {
      std::string k = inner.String(what);
      m[std::move(k)] = inner.String(what);
    }
    return m;
  }
  [[noreturn]] void Fail(std::uint64_t at, const std::string& message) const { throw CorruptFileError(*path_, at, message); }

 private:
  void Need(std::uint64_t n, const char* what) const {
    if (n > remaining()) {
      Fail(offset(), fmt::format("{} needs {} bytes but only {} remain in its record or file (truncated or damaged)",
                                 what, n, remaining()));
    }
  }
  std::string_view b_;
  std::uint64_t base_;
  std::size_t pos_ = 0;
  const std::string* path_;
};

/// Reads the next record's opcode and body; `at` receives the record's offset.
std::pair<std::uint8_t, Cursor> NextRecord(Cursor* c, std::uint64_t* at, const std::string* path) {
  *at = c->offset();
  const auto opcode = c->Get<std::uint8_t>("a record's opcode");
  const auto length = c->Get<std::uint64_t>("a record's length");
  const std::uint64_t body_at = c->offset();
  return {opcode, Cursor(c->Bytes(length, "a record's body"), body_at, path)};
}

/// The records that may appear both at the top level and inside chunks.
void ParseDataRecord(std::uint8_t opcode, std::uint64_t at, Cursor body, McapContent* content) {
  switch (opcode) {
    case kSchema: {
      McapSchema s;
      s.id = body.Get<std::uint16_t>("schema id");
      s.name = body.String("schema name");
      s.encoding = body.String("schema encoding");
      s.data = body.String("schema data");
      if (s.id == 0) body.Fail(at, "schema id 0 is reserved");
      content->schemas[s.id] = std::move(s);
      break;
    }
    case kChannel: {
      McapChannel ch;
      ch.id = body.Get<std::uint16_t>("channel id");
      ch.schema_id = body.Get<std::uint16_t>("channel schema id");
      ch.topic = body.String("channel topic");
      ch.message_encoding = body.String("channel message encoding");
      ch.metadata = body.StringMap("channel metadata");
      if (ch.schema_id != 0 && content->schemas.count(ch.schema_id) == 0) {
        body.Fail(at, fmt::format("channel {} refers to schema {}, which was not defined before it", ch.id, ch.schema_id));
      }
      content->channels[ch.id] = std::move(ch);
      break;
    }
    case kMessage: {
      McapMessage m;
      m.offset = at;
      m.channel_id = body.Get<std::uint16_t>("message channel id");
      m.sequence = body.Get<std::uint32_t>("message sequence");
      m.log_time_ns = body.Get<std::uint64_t>("message log time");
      m.publish_time_ns = body.Get<std::uint64_t>("message publish time");
      m.data = std::string(body.Bytes(body.remaining(), "message data"));
      if (content->channels.count(m.channel_id) == 0) {
        body.Fail(at, fmt::format("a message on channel {}, which was not defined before it", m.channel_id));
      }
      content->messages.push_back(std::move(m));
      break;
    }
    default:
      break;  // indexes and other records are not needed to read the content
  }
}

}  // namespace

const McapChannel* McapContent::FindChannel(std::string_view topic) const {
  for (const auto& [id, ch] : channels) {
    if (ch.topic == topic) return &ch;
  }
  return nullptr;
}

const McapMetadata* McapContent::FindMetadata(std::string_view name) const {
  for (const McapMetadata& m : metadata) {
    if (m.name == name) return &m;
  }
  return nullptr;
}

McapContent ParseMcap(std::string_view bytes, const std::string& path) {
  if (bytes.size() < kMagic.size() || bytes.substr(0, kMagic.size()) != kMagic) {
    throw CorruptFileError(path, 0, "not an MCAP file: it does not start with the MCAP magic bytes");
  }
  McapContent content;
  Cursor file(bytes.substr(kMagic.size()), kMagic.size(), &path);
  bool header = false, data_end = false;
  for (;;) {
    if (file.done()) file.Fail(file.offset(), "the file ends before its footer (truncated)");
    std::uint64_t at = 0;
    auto [opcode, body] = NextRecord(&file, &at, &path);
    if (!header && opcode != kHeader) file.Fail(at, fmt::format("expected the header record first, found opcode 0x{:02x}", opcode));
    if (opcode == kHeader) {
      if (header) file.Fail(at, "a second header record");
      header = true;
      content.profile = body.String("header profile");
      content.library = body.String("header library");
    } else if (opcode == kFooter) {
      const auto summary_start = body.Get<std::uint64_t>("footer summary start");
      body.Get<std::uint64_t>("footer summary offset start");
      const std::uint64_t crc_at = body.offset();
      const auto summary_crc = body.Get<std::uint32_t>("footer summary CRC");
      if (!data_end) file.Fail(at, "the footer comes before the data end record");
      if (summary_crc != 0 && summary_start != 0) {
        if (summary_start > at) file.Fail(at, fmt::format("the footer's summary start {} lies after the footer", summary_start));
        // CRC of the summary section through the footer's summary offset start field.
        const std::uint32_t crc = Crc32(bytes.substr(summary_start, crc_at - summary_start));
        if (crc != summary_crc) {
          file.Fail(summary_start, fmt::format("the summary's CRC-32 is {:08x}, the footer says {:08x}", crc, summary_crc));
        }
      }
      break;
    } else if (opcode == kDataEnd) {
      const auto crc = body.Get<std::uint32_t>("data end CRC");
      if (crc != 0) {
        const std::uint32_t actual = Crc32(bytes.substr(0, at));
        if (actual != crc) {
          file.Fail(at, fmt::format("the data section's CRC-32 is {:08x}, the data end record says {:08x}", actual, crc));
        }
      }
      data_end = true;
    } else if (data_end) {
      continue;  // the summary repeats schemas and channels and indexes the data section
    } else if (opcode == kChunk) {
      body.Get<std::uint64_t>("chunk start time");
      body.Get<std::uint64_t>("chunk end time");
      const auto uncompressed_size = body.Get<std::uint64_t>("chunk uncompressed size");
      const auto crc = body.Get<std::uint32_t>("chunk CRC");
      const std::string compression = body.String("chunk compression");
      const auto size = body.Get<std::uint64_t>("chunk records length");
      const std::uint64_t records_at = body.offset();
      const std::string_view records = body.Bytes(size, "chunk records");
      if (!compression.empty()) file.Fail(at, fmt::format("chunk compressed with '{}'; only uncompressed chunks are read", compression));
      if (uncompressed_size != size) {
        file.Fail(at, fmt::format("chunk of {} bytes claims {} uncompressed bytes", size, uncompressed_size));
      }
      if (crc != 0 && Crc32(records) != crc) file.Fail(records_at, fmt::format("chunk CRC-32 mismatch (chunk at byte {})", at));
      Cursor inner(records, records_at, &path);
      while (!inner.done()) {
        std::uint64_t inner_at = 0;
        auto [inner_opcode, inner_body] = NextRecord(&inner, &inner_at, &path);
        ParseDataRecord(inner_opcode, inner_at, inner_body, &content);
      }
    } else if (opcode == kMetadata) {
      McapMetadata m;
      m.offset = at;
      m.name = body.String("metadata name");
      m.metadata = body.StringMap("metadata map");
      content.metadata.push_back(std::move(m));
    } else {
      ParseDataRecord(opcode, at, body, &content);
    }
  }
  if (file.remaining() != kMagic.size() || file.Bytes(kMagic.size(), "the closing magic") != kMagic) {
    file.Fail(file.offset(), "the file does not end with the MCAP magic bytes right after its footer");
  }
  return content;
}

McapContent ReadMcap(const std::string& path) { return ParseMcap(ReadInputFile(path), path); }

}  // namespace rotorguard::io
