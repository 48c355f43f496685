#pragma once
/// MCAP files (https://mcap.dev/spec, format version 0): the log container Foxglove and
/// PlotJuggler open. Written to the specification, since Debian packages no C++ MCAP library:
/// a header, schemas and channels, uncompressed chunks of messages each followed by its message
/// indexes, metadata, then a summary (schemas, channels, statistics, chunk and metadata indexes,
/// summary offsets) and the footer, with the data-section, chunk and summary CRC-32s filled in.
/// The reader checks all of it and names the byte offset of the first fault.
#include <cstdint>
#include <map>
#include <string>
#include <string_view>
#include <vector>

namespace rotorguard::io {

/// CRC-32 (IEEE 802.3, reflected polynomial 0xEDB88320), as MCAP uses; `crc` continues a running value.
std::uint32_t Crc32(std::string_view data, std::uint32_t crc = 0);

struct McapWriterOptions {
  std::string profile;  ///< "" (no well-known profile): messages are JSON with jsonschema schemas
  std::string library = "rotorguard";
  std::size_t chunk_size = 1u << 20;  ///< a chunk is closed once its records exceed this [bytes], > 0
};

/// Builds an MCAP file in memory; Finish() returns its bytes.
class McapWriter {
 public:
  explicit McapWriter(const McapWriterOptions& options = {});
  /// Returns the schema id (1, 2, ...).
  std::uint16_t AddSchema(std::string_view name, std::string_view encoding, std::string_view data);
  /// Returns the channel id (0, 1, ...). `schema_id` must come from AddSchema.
  std::uint16_t AddChannel(std::uint16_t schema_id, std::string_view topic, std::string_view message_encoding,
                           const std::map<std::string, std::string>& metadata = {});
  /// Messages of one channel in non-decreasing log time [ns].
  void AddMessage(std::uint16_t channel_id, std::uint64_t log_time_ns, std::string_view data);
  void AddMetadata(std::string_view name, const std::map<std::string, std::string>& metadata);
  /// Closes the data section and writes the summary and footer. The writer is spent afterwards.
  std::string Finish();

 private:
  void CloseChunk();

  McapWriterOptions options_;
  std::string out_;
  std::string schemas_, channels_;  // the records again, for the summary
  std::uint16_t schemas_count_ = 0;
  std::string chunk_;               // records of the open chunk
  std::uint64_t chunk_start_ns_ = 0, chunk_end_ns_ = 0;
  std::map<std::uint16_t, std::vector<std::pair<std::uint64_t, std::uint64_t>>> chunk_index_;  // per channel: time, offset
  std::string chunk_indexes_, metadata_indexes_;
  std::map<std::uint16_t, std::uint64_t> channel_counts_;
  std::vector<std::uint32_t> sequence_;
  std::uint64_t message_count_ = 0, start_ns_ = 0, end_ns_ = 0;
  std::uint32_t chunk_count_ = 0, metadata_count_ = 0;
  bool finished_ = false;
};

struct McapSchema {
  std::uint16_t id = 0;
  std::string name, encoding, data;
};
struct McapChannel {
  std::uint16_t id = 0, schema_id = 0;
  std::string topic, message_encoding;
  std::map<std::string, std::string> metadata;
};
struct McapMessage {
  std::uint64_t offset = 0;  ///< of its record in the file
  std::uint16_t channel_id = 0;
  std::uint32_t sequence = 0;
  std::uint64_t log_time_ns = 0, publish_time_ns = 0;
  std::string data;
};
struct McapMetadata {
  std::uint64_t offset = 0;  ///< of its record in the file
  std::string name;
  std::map<std::string, std::string> metadata;
};

/// What a reader found: the records of the data section (messages in file order).
struct McapContent {
  std::map<std::uint16_t, McapSchema> schemas;
  std::map<std::uint16_t, McapChannel> channels;
  std::vector<McapMessage> messages;
  std::vector<McapMetadata> metadata;
  std::string profile, library;
  /// The channel with this topic; nullptr when there is none.
  const McapChannel* FindChannel(std::string_view topic) const;
  /// The metadata record of this name; nullptr when there is none.
  const McapMetadata* FindMetadata(std::string_view name) const;
};

/// Parses and checks an MCAP file: magic at both ends, every record inside the file, uncompressed
/// chunks with matching CRC, the data-section CRC, the footer's summary CRC, messages on known
/// channels. Throws CorruptFileError (config_node.h) naming `path` and the byte offset.
McapContent ParseMcap(std::string_view bytes, const std::string& path);
/// ReadInputFile then ParseMcap.
McapContent ReadMcap(const std::string& path);

/// Base64 (RFC 4648) of bytes: how JSON-encoded Foxglove messages carry binary fields.
std::string Base64Encode(std::string_view bytes);

}  // namespace rotorguard::io
