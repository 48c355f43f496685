// The log formats' readers and writers: numeric CSV, CRC-32, base64 and MCAP, each against an
// independent truth (published check values, RFC test vectors, the MCAP specification's layout)
// and against damaged input, which must be rejected at the right byte.
#include <cstring>
#include <filesystem>
#include <stdexcept>
#include <string>
#include <vector>

#include <gtest/gtest.h>

#include "rotorguard/io/config_node.h"
#include "rotorguard/io/csv.h"
#include "rotorguard/io/files.h"
#include "rotorguard/io/mcap.h"
#include "test_util.h"

namespace rotorguard::io {
namespace {

template <typename F>
CorruptFileError CatchCorrupt(F&& fn) {
  try {
    fn();
  } catch (const CorruptFileError& e) {
    return e;
  }
  ADD_FAILURE() << "expected a CorruptFileError";
  return CorruptFileError("", 0, "");
}

// Temporary folders: new and empty, distinct side by side, removed with their content when they
// go, also when an exception unwinds past them.
TEST(TemporaryFolder, IsNewDistinctAndRemovedWithItsContentEvenOnAnException) {
  namespace fs = std::filesystem;
  std::string a_path, b_path;
  {
    const TemporaryFolder a("rg-test"), b("rg-test");
    a_path = a.path();
    b_path = b.path();
    EXPECT_NE(a_path, b_path);
    EXPECT_TRUE(fs::is_directory(a_path) && fs::is_empty(a_path));
    fs::create_directories(fs::path(a_path) / "sub");
    WriteFileAtomically((fs::path(a_path) / "sub" / "f.txt").string(), "x");
  }
  EXPECT_FALSE(fs::exists(a_path));
  EXPECT_FALSE(fs::exists(b_path));
  std::string c_path;
  try {
    const TemporaryFolder c("rg-test");
    c_path = c.path();
    throw std::runtime_error("unwind");
  } catch (const std::runtime_error&) {
  }
  EXPECT_FALSE(c_path.empty());
  EXPECT_FALSE(fs::exists(c_path));
}

TEST(NumericCsv, ParsesHeaderAndColumns) {
  const NumericTable t = ParseNumericCsv("t,a,b\n0,1.5,-2\n0.01,2.5e-3,3\n", "log.csv");
  ASSERT_EQ(t.columns, (std::vector<std::string>{"t", "a", "b"}));
  ASSERT_EQ(t.rows(), 2u);
  EXPECT_EQ(t.Column("a")[1], 2.5e-3);
  EXPECT_EQ(t.Column("b")[0], -2.0);
  EXPECT_EQ(t.Find("c"), -1);
  EXPECT_THROW(t.Column("c"), std::out_of_range);
}

TEST(NumericCsv, HeaderOnlyIsAnEmptyTable) {
  const NumericTable t = ParseNumericCsv("t,a\n", "log.csv");
  EXPECT_EQ(t.columns.size(), 2u);
  EXPECT_EQ(t.rows(), 0u);
}

TEST(NumericCsv, TruncatedRowNamesItsByteOffset) {
  const std::string text = "t,a,b\n0,1,2\n0.01,3";  // cut in the middle of the second row
  const CorruptFileError e = CatchCorrupt([&] { ParseNumericCsv(text, "log.csv"); });
  EXPECT_EQ(e.byte_offset(), text.size());
  EXPECT_NE(std::string(e.what()).find("log.csv: corrupt at byte 18: line 3 ends after 2 of 3 fields"), std::string::npos)
      << e.what();
}

TEST(NumericCsv, LastRowWithoutNewlineIsTruncated) {
  const std::string text = "t,a\n0,1\n0.01,3";
  EXPECT_EQ(CatchCorrupt([&] { ParseNumericCsv(text, "log.csv"); }).byte_offset(), text.size());
}

TEST(NumericCsv, BadFieldNamesLineColumnAndOffset) {
  const std::string text = "t,a\n0,1\n0.01,x\n";
  const CorruptFileError e = CatchCorrupt([&] { ParseNumericCsv(text, "log.csv"); });
  EXPECT_EQ(e.byte_offset(), text.find('x'));
  EXPECT_NE(e.message().find("line 3, column 'a'"), std::string::npos) << e.what();
}

TEST(NumericCsv, NonFiniteAndExtraFieldsAreRejected) {
  EXPECT_EQ(CatchCorrupt([] { ParseNumericCsv("t,a\n0,nan\n", "f"); }).byte_offset(), 6u);
  EXPECT_EQ(CatchCorrupt([] { ParseNumericCsv("t,a\n0,inf\n", "f"); }).byte_offset(), 6u);
  EXPECT_EQ(CatchCorrupt([] { ParseNumericCsv("t,a\n0,1,2\n", "f"); }).byte_offset(), 7u);
  EXPECT_EQ(CatchCorrupt([] { ParseNumericCsv("", "f"); }).byte_offset(), 0u);
  EXPECT_EQ(CatchCorrupt([] { ParseNumericCsv("t,,a\n", "f"); }).byte_offset(), 2u);
}

TEST(Crc32, MatchesTheStandardCheckValue) {
  // The CRC-32 (ISO-HDLC) catalogue's check value for "123456789".
  EXPECT_EQ(Crc32("123456789"), 0xCBF43926u);
  EXPECT_EQ(Crc32(""), 0u);
  // Continuing a running value equals one pass over the concatenation.
  EXPECT_EQ(Crc32("6789", Crc32("12345")), 0xCBF43926u);
}

TEST(Base64, MatchesRfc4648Vectors) {
  EXPECT_EQ(Base64Encode(""), "");
  EXPECT_EQ(Base64Encode("f"), "Zg==");
  EXPECT_EQ(Base64Encode("fo"), "Zm8=");
  EXPECT_EQ(Base64Encode("foo"), "Zm9v");
  EXPECT_EQ(Base64Encode("foob"), "Zm9vYg==");
  EXPECT_EQ(Base64Encode("fooba"), "Zm9vYmE=");
  EXPECT_EQ(Base64Encode("foobar"), "Zm9vYmFy");
}

/// A small file: two channels, messages spread over several chunks, one metadata record.
std::string SampleMcap(std::size_t chunk_size = 200) {
  McapWriterOptions o;
  o.chunk_size = chunk_size;
  McapWriter w(o);
  const std::uint16_t schema = w.AddSchema("test.Value", "jsonschema", R"({"type":"object"})");
  const std::uint16_t a = w.AddChannel(schema, "/a", "json");
  const std::uint16_t b = w.AddChannel(schema, "/b", "json", {{"unit", "m"}});
  for (int k = 0; k < 20; ++k) {
    w.AddMessage(a, 1000u * static_cast<std::uint64_t>(k), "{\"v\":" + std::to_string(k) + "}");
    if (k % 2 == 0) w.AddMessage(b, 1000u * static_cast<std::uint64_t>(k) + 1, "{\"w\":" + std::to_string(k) + "}");
  }
  w.AddMetadata("run", {{"scenario", "hover"}, {"seed", "7"}});
  return w.Finish();
}

std::uint64_t ReadU64(const std::string& s, std::size_t at) {
  std::uint64_t v = 0;
  for (int i = 0; i < 8; ++i) v |= static_cast<std::uint64_t>(static_cast<std::uint8_t>(s[at + i])) << (8 * i);
  return v;
}

TEST(Mcap, RoundTripsSchemasChannelsMessagesAndMetadata) {
  const std::string bytes = SampleMcap();
  const McapContent c = ParseMcap(bytes, "f.mcap");
  EXPECT_EQ(c.library, "rotorguard");
  ASSERT_EQ(c.schemas.size(), 1u);
  EXPECT_EQ(c.schemas.at(1).name, "test.Value");
  ASSERT_EQ(c.channels.size(), 2u);
  ASSERT_NE(c.FindChannel("/b"), nullptr);
  EXPECT_EQ(c.FindChannel("/b")->metadata.at("unit"), "m");
  ASSERT_EQ(c.messages.size(), 30u);
  EXPECT_EQ(c.messages.front().data, "{\"v\":0}");
  EXPECT_EQ(c.messages.front().log_time_ns, 0u);
  // Sequence numbers count per channel.
  int seen_b = 0;
  for (const McapMessage& m : c.messages) {
    if (m.channel_id == c.FindChannel("/b")->id) {
      EXPECT_EQ(m.sequence, static_cast<std::uint32_t>(seen_b++));
    }
  }
  ASSERT_NE(c.FindMetadata("run"), nullptr);
  EXPECT_EQ(c.FindMetadata("run")->metadata.at("seed"), "7");
}

TEST(Mcap, LayoutFollowsTheSpecification) {
  const std::string bytes = SampleMcap();
  // Magic at both ends; the footer (opcode 0x02, 20-byte body) right before the closing magic.
  ASSERT_EQ(bytes.substr(0, 8), std::string("\x89MCAP0\r\n", 8));
  ASSERT_EQ(bytes.substr(bytes.size() - 8), std::string("\x89MCAP0\r\n", 8));
  const std::size_t footer = bytes.size() - 8 - 29;
  ASSERT_EQ(static_cast<std::uint8_t>(bytes[footer]), 0x02);
  EXPECT_EQ(ReadU64(bytes, footer + 1), 20u);
  const std::uint64_t summary_start = ReadU64(bytes, footer + 9);
  const std::uint64_t summary_offset_start = ReadU64(bytes, footer + 17);
  ASSERT_GT(summary_start, 8u);
  ASSERT_GT(summary_offset_start, summary_start);
  // The summary starts right after the data end record (0x0F, 4-byte CRC of everything before it).
  ASSERT_EQ(static_cast<std::uint8_t>(bytes[summary_start - 13]), 0x0F);
  std::uint32_t data_crc = 0;
  std::memcpy(&data_crc, bytes.data() + summary_start - 4, 4);
  EXPECT_EQ(data_crc, Crc32(std::string_view(bytes).substr(0, summary_start - 13)));
  // Summary offsets: one per group, each pointing at a run of records of its opcode.
  int groups = 0;
  for (std::size_t at = summary_offset_start; at < footer; at += 9 + 17, ++groups) {
    ASSERT_EQ(static_cast<std::uint8_t>(bytes[at]), 0x0E);
    const auto opcode = static_cast<std::uint8_t>(bytes[at + 9]);
    const std::uint64_t start = ReadU64(bytes, at + 10);
    EXPECT_EQ(static_cast<std::uint8_t>(bytes[start]), opcode) << "group of opcode " << int(opcode);
  }
  EXPECT_EQ(groups, 5);  // schemas, channels, statistics, chunk indexes, metadata indexes
}

TEST(Mcap, SeveralChunksWhenMessagesExceedTheChunkSize) {
  const std::string small = SampleMcap(200), single = SampleMcap(1 << 20);
  const auto count_chunks = [](const std::string& s) {
    // Chunk index records (0x08) live in the summary; count them by walking its records.
    const std::size_t footer = s.size() - 8 - 29;
    std::size_t at = ReadU64(s, footer + 9);
    int n = 0;
    while (at < footer) {
      if (static_cast<std::uint8_t>(s[at]) == 0x08) ++n;
      at += 9 + ReadU64(s, at + 1);
    }
    return n;
  };
  EXPECT_GT(count_chunks(small), 2);
  EXPECT_EQ(count_chunks(single), 1);
  EXPECT_EQ(ParseMcap(small, "f").messages.size(), ParseMcap(single, "f").messages.size());
}

TEST(Mcap, TruncatedFileIsRejectedWithAnOffset) {
  const std::string bytes = SampleMcap();
  for (const std::size_t keep : {std::size_t{4}, std::size_t{30}, bytes.size() / 2, bytes.size() - 9, bytes.size() - 1}) {
    const CorruptFileError e = CatchCorrupt([&] { ParseMcap(bytes.substr(0, keep), "f.mcap"); });
    EXPECT_LE(e.byte_offset(), keep) << "kept " << keep << ": " << e.what();
  }
}

TEST(Mcap, AFlippedByteInAChunkFailsItsCrc) {
  std::string bytes = SampleMcap();
  const std::size_t at = bytes.find("{\"v\":3}");
  ASSERT_NE(at, std::string::npos);
  bytes[at + 5] = '4';  // same length, different content
  const CorruptFileError e = CatchCorrupt([&] { ParseMcap(bytes, "f.mcap"); });
  EXPECT_NE(e.message().find("chunk CRC-32 mismatch"), std::string::npos) << e.what();
  EXPECT_LE(e.byte_offset(), at);
}

TEST(Mcap, AFlippedByteInTheSummaryFailsItsCrc) {
  std::string bytes = SampleMcap();
  const std::size_t footer = bytes.size() - 8 - 29;
  const std::uint64_t summary_start = ReadU64(bytes, footer + 9);
  bytes[summary_start + 20] ^= 0x01;
  const CorruptFileError e = CatchCorrupt([&] { ParseMcap(bytes, "f.mcap"); });
  EXPECT_NE(e.message().find("summary's CRC-32"), std::string::npos) << e.what();
  EXPECT_EQ(e.byte_offset(), summary_start);
}

TEST(Mcap, NotAnMcapFile) {
  const CorruptFileError e = CatchCorrupt([] { ParseMcap("t,a\n0,1\n", "log.csv"); });
  EXPECT_EQ(e.byte_offset(), 0u);
  EXPECT_NE(e.message().find("not an MCAP file"), std::string::npos);
}

TEST(Mcap, WriterRejectsUnknownIds) {
  McapWriter w;
  EXPECT_THROW(w.AddChannel(1, "/a", "json"), std::invalid_argument);
  const std::uint16_t s = w.AddSchema("x", "jsonschema", "{}");
  const std::uint16_t c = w.AddChannel(s, "/a", "json");
  EXPECT_THROW(w.AddMessage(static_cast<std::uint16_t>(c + 1), 0, "{}"), std::invalid_argument);
}

}  // namespace
}  // namespace rotorguard::io
