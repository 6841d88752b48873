// The pieces every TUM text reader and every timestamp pairing rests on: where errors point,
// and which pairs each limit admits.
#include <gtest/gtest.h>

#include <fstream>
#include <string>

#include "flowfusion/core/error.h"
#include "flowfusion/io/tum_text.h"
#include "testing/test_util.h"

namespace ff {
namespace {

std::string writeFile(const testing::TempDir& tmp, const std::string& text) {
  const std::string p = (tmp.path() / "records.txt").string();
  std::ofstream(p) << text;
  return p;
}

template <typename F>
std::string inputErrorOf(F&& f) {
  try {
    f();
  } catch (const InputError& e) {
    return e.what();
  }
  ADD_FAILURE() << "no InputError";
  return "";
}

TEST(RecordReader, SkipsCommentsAndCountsEveryLine) {
  testing::TempDir tmp;
  const auto p = writeFile(tmp, "# header\n\n  # indented\r\n1.0 a\r\n2.0 b\n");
  RecordReader in(p, "test list", "timestamp name");
  ASSERT_TRUE(in.next());
  EXPECT_DOUBLE_EQ(in.timestamp(), 1.0);
  std::string name;
  in.fields() >> name;
  EXPECT_EQ(name, "a");
  ASSERT_TRUE(in.next());
  EXPECT_EQ(inputErrorOf([&] { in.fail("bad"); }), p + ":5: bad");
  EXPECT_FALSE(in.next());
  // Once read, the file as a whole is at fault, not its last line.
  EXPECT_EQ(inputErrorOf([&] { in.fail("holds too little"); }), p + ": holds too little");
}

TEST(RecordReader, MalformedLineQuotesFormatAndLine) {
  testing::TempDir tmp;
  const auto p = writeFile(tmp, "one a\n");
  RecordReader in(p, "test list", "timestamp name");
  ASSERT_TRUE(in.next());
  EXPECT_EQ(inputErrorOf([&] { in.timestamp(); }), p + ":1: expected 'timestamp name', got 'one a'");
}

TEST(RecordReader, TimestampsMustIncrease) {
  testing::TempDir tmp;
  const auto secondTimestampError = [&](const std::string& text) {
    RecordReader in(writeFile(tmp, text), "test list", "timestamp name");
    EXPECT_TRUE(in.next() && in.timestamp() > 0 && in.next());
    return inputErrorOf([&] { in.timestamp(); });
  };
  const std::string dup = secondTimestampError("1.5 a\n1.5 b\n");
  EXPECT_NE(dup.find(":2: timestamp 1.500000 is a duplicate"), std::string::npos) << dup;
  const std::string back = secondTimestampError("2 a\n1 b\n");
  EXPECT_NE(back.find(":2: timestamp 1.000000 is earlier"), std::string::npos) << back;
}

TEST(RecordReader, MissingFileNamesKind) {
  testing::TempDir tmp;
  const std::string p = (tmp.path() / "absent.txt").string();
  EXPECT_EQ(inputErrorOf([&] { RecordReader(p, "test list", "timestamp name"); }), p + ": cannot open test list");
}

TEST(Associate, NearestWithinLimitEachIndexOnce) {
  // Colour 1.00 and 1.01 both nearest to depth 1.004: the closer (1.00) wins, 1.01 takes 1.025.
  for (const StampLimit limit : {StampLimit::kInclusive, StampLimit::kExclusive}) {
    const auto pairs = associate({1.00, 1.01, 1.50}, {0.90, 1.004, 1.025, 1.53}, 0.02, limit);
    ASSERT_EQ(pairs.size(), 2u);
    EXPECT_EQ(pairs[0], std::make_pair(size_t{0}, size_t{1}));
    EXPECT_EQ(pairs[1], std::make_pair(size_t{1}, size_t{2}));
    EXPECT_TRUE(associate({1.0}, {1.03}, 0.02, limit).empty());
  }
}

TEST(Associate, LimitDecidesAnExactDifference) {
  // Differences of exactly 0.5 on either side (all values exact in binary).
  EXPECT_EQ(associate({1.0}, {0.5}, 0.5, StampLimit::kInclusive).size(), 1u);
  EXPECT_EQ(associate({1.0}, {1.5}, 0.5, StampLimit::kInclusive).size(), 1u);
  EXPECT_TRUE(associate({1.0}, {0.5}, 0.5, StampLimit::kExclusive).empty());
  EXPECT_TRUE(associate({1.0}, {1.5}, 0.5, StampLimit::kExclusive).empty());
}

}  // namespace
}  // namespace ff
