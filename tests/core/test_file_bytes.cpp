#include <gtest/gtest.h>

#include <fstream>

#include "flowfusion/core/file_bytes.h"
#include "testing/test_util.h"

namespace ff {
namespace {

TEST(FileBytes, AWholeFileIsReadByteForByteAndWhatIsNoFileGivesNothing) {
  testing::TempDir dir;
  const std::string path = (dir.path() / "bytes.bin").string();
  const std::string written("\x89PNG\0\r\n\xff tail", 13);
  std::ofstream(path, std::ios::binary) << written;
  const std::optional<std::string> read = readFileBytes(path);
  ASSERT_TRUE(read);
  EXPECT_EQ(*read, written);
  std::ofstream((dir.path() / "empty").string(), std::ios::binary);
  EXPECT_EQ(readFileBytes((dir.path() / "empty").string()), std::string());
  EXPECT_FALSE(readFileBytes((dir.path() / "missing").string()));
  EXPECT_FALSE(readFileBytes(dir.path().string()));  // a folder
}

TEST(FileBytes, BigEndianNumbersReadMostSignificantByteFirst) {
  const unsigned char bytes[] = {0x12, 0x34, 0x56, 0x78, 0xff, 0xff, 0xff, 0xfe};
  EXPECT_EQ(bigEndian32(bytes), 0x12345678u);
  EXPECT_EQ(bigEndian32(bytes + 4), 0xfffffffeu);
}

}  // namespace
}  // namespace ff
