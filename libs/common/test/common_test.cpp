#include <gtest/gtest.h>
#include <malloc.h>

#include <cstdlib>

#include <filesystem>
#include <fstream>
#include <set>

#include "concert/common/clock.hpp"
#include "concert/common/enum_map.hpp"
#include "concert/common/memory.hpp"
#include "concert/common/text.hpp"

namespace concert {
namespace {

enum class Colour { kRed, kGreen, kBlue };
enum Wire : int { WIRE_RED = 10, WIRE_GREEN = 11 };

TEST(EnumMap, BothDirectionsAndMissingRows) {
  constexpr EnumMap kColours{std::array{std::pair{Colour::kRed, WIRE_RED}, std::pair{Colour::kGreen, WIRE_GREEN}}};
  static_assert(kColours.to(Colour::kGreen) == WIRE_GREEN);
  EXPECT_EQ(kColours.to(Colour::kRed), WIRE_RED);
  EXPECT_EQ(kColours.from(WIRE_GREEN), Colour::kGreen);
  EXPECT_FALSE(kColours.to(Colour::kBlue).has_value());
  EXPECT_FALSE(kColours.from(static_cast<Wire>(12)).has_value());
  EXPECT_EQ(kColours.pairs().size(), 2u);
}

TEST(Text, JoinAnyRangeOfStrings) {
  EXPECT_EQ(join(std::vector<std::string>{}), "");
  EXPECT_EQ(join(std::vector<std::string>{"a"}), "a");
  EXPECT_EQ(join(std::set<std::string>{"b", "a"}), "a, b");
  EXPECT_EQ(join(std::vector<const char*>{"x", "y", "z"}, "|"), "x|y|z");
}

TEST(Text, SplitLeavesOutEmptyPieces) {
  EXPECT_EQ(split("a,b"), (std::vector<std::string>{"a", "b"}));
  EXPECT_EQ(split(",a,,b,"), (std::vector<std::string>{"a", "b"}));
  EXPECT_TRUE(split("").empty());
  EXPECT_EQ(split("x y", ' '), (std::vector<std::string>{"x", "y"}));
}

TEST(Text, InvalidUtf8At) {
  EXPECT_EQ(invalid_utf8_at(""), std::nullopt);
  EXPECT_EQ(invalid_utf8_at("plain ascii"), std::nullopt);
  EXPECT_EQ(invalid_utf8_at("caf\xc3\xa9 \xe2\x82\xac \xf0\x9f\xa4\x96"),
            std::nullopt);                                       // é € 🤖
  EXPECT_EQ(invalid_utf8_at("ab\x80"), 2u);                      // stray continuation byte
  EXPECT_EQ(invalid_utf8_at("x\xf0\x9f\xa4"), 1u);               // cut short at the end
  EXPECT_EQ(invalid_utf8_at(std::string("\xf0\0\0\0", 4)), 0u);  // a NUL is no continuation
  EXPECT_EQ(invalid_utf8_at("\xc0\xaf"), 0u);                    // overlong '/'
  EXPECT_EQ(invalid_utf8_at("\xed\xa0\x80"), 0u);                // surrogate U+D800
  EXPECT_EQ(invalid_utf8_at("\xf4\x90\x80\x80"), 0u);            // above U+10FFFF
  // YAML's printable set: tab, LF and CR pass; NUL, other C0 controls and DEL do not.
  EXPECT_EQ(yaml_control_character_at("a: b\tc\r\nd: \"\xc3\xa9\"\n"), std::nullopt);
  EXPECT_EQ(yaml_control_character_at(std::string("drill@mani\0_pc: x", 18)), 10u);
  EXPECT_EQ(yaml_control_character_at("x\x1b[0m"), 1u);
  EXPECT_EQ(yaml_control_character_at("ab\x7f"), 2u);
  EXPECT_EQ(invalid_utf8_at("\xff"), 0u);
}

TEST(Text, ReadFileNamesTheFileItCannotOpen) {
  const auto file = std::filesystem::temp_directory_path() / "concert_common_test.txt";
  std::ofstream(file) << "line 1\nline 2\n";
  EXPECT_EQ(read_file(file), "line 1\nline 2\n");
  std::filesystem::remove(file);
  try {
    read_file(file, "world");
    FAIL() << "no error for a missing file";
  } catch (const std::runtime_error& e) {
    EXPECT_EQ(std::string(e.what()), "world file '" + file.string() + "' cannot be opened");
  }
}

TEST(Clock, NowIsWallClockNanoseconds) {
  const int64_t a = now_ns();
  const int64_t b = now_ns();
  EXPECT_LE(a, b);
  EXPECT_GT(a, int64_t{1'600'000'000} * 1'000'000'000);  // after September 2020
}

// After a large mapped block is freed, a 1 MiB block is still mapped on its own (returned to the
// system when freed), not carved from the heap: glibc's moving threshold would have risen to 8 MiB.
TEST(Memory, FixedMallocThresholdsMapLargeBlocksAfterALargerOneWasFreed) {
  ASSERT_TRUE(fix_malloc_thresholds());
  auto* big = static_cast<volatile char*>(std::malloc(8u << 20));
  ASSERT_NE(big, nullptr);
  big[0] = 1;
  std::free(const_cast<char*>(big));
  const auto mapped_before = mallinfo2().hblks;
  auto* block = static_cast<volatile char*>(std::malloc(1u << 20));
  ASSERT_NE(block, nullptr);
  block[0] = 1;
  EXPECT_EQ(mallinfo2().hblks, mapped_before + 1) << "the 1 MiB block came from the heap";
  std::free(const_cast<char*>(block));
}

}  // namespace
}  // namespace concert
