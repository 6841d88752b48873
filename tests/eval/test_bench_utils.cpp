#include <gtest/gtest.h>

#include <cmath>

#include "flowfusion/eval/bench_utils.h"

namespace ff::eval {
namespace {

TEST(TextTable, AlignsNumbersRightAndTextLeft) {
  TextTable t({"method", "ATE m"});
  t.addRow({"rgbd", TextTable::num(0.0325, 4)});
  t.addRow({"flowfusion", TextTable::num(12.5, 1)});
  t.addRow({"none", TextTable::num(NAN)});
  t.addRow({"peer"});  // padded with an empty cell
  // The numeric column's header is right-aligned; no line has trailing blanks.
  EXPECT_EQ(t.str(),
            "method       ATE m\n"
            "------------------\n"
            "rgbd        0.0325\n"
            "flowfusion    12.5\n"
            "none             -\n"
            "peer\n");
  EXPECT_THROW(t.addRow({"a", "b", "c"}), std::invalid_argument);
}

}  // namespace
}  // namespace ff::eval
