#include <gtest/gtest.h>

#include <vector>

#include "flowfusion/core/process_memory.h"

namespace ff {
namespace {

TEST(PeakResident, GrowsWhenMemoryIsTouched) {
  const double before = peakResidentMiB();
  EXPECT_GT(before, 0);
  std::vector<char> block(64 << 20, 1);  // 64 MiB, written so it is resident
  volatile char sink = block[block.size() / 2];
  (void)sink;
  EXPECT_GE(peakResidentMiB(), before + 32);
}

}  // namespace
}  // namespace ff
