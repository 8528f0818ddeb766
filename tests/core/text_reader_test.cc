#include "semslam/core/text_reader.h"

#include <gtest/gtest.h>

#include <fstream>

#include "semslam/core/atomic_file.h"
#include "support/test_support.h"

namespace semslam {
namespace {

TEST(TextReader, ParsesNumbersAndReportsLocation) {
  const SourceLocation where{"calib.txt", 3};
  EXPECT_DOUBLE_EQ(ParseDouble("7.188560000000e+02", where, "P0[0]"), 718.856);
  EXPECT_DOUBLE_EQ(ParseDouble("+1.5", where, "x"), 1.5);
  EXPECT_EQ(ParseInt("42", where, "n"), 42);
  try {
    ParseDouble("7.1x", where, "P0[2]");
    FAIL() << "expected InputError";
  } catch (const InputError& e) {
    EXPECT_STREQ(e.what(), "calib.txt:3: field 'P0[2]': '7.1x' is not a number");
  }
  EXPECT_THROW(ParseDouble("nan", where, "x"), InputError);
  EXPECT_THROW(ParseDouble("", where, "x"), InputError);
  EXPECT_TRUE(std::isnan(ParseDoubleAllowNonFinite("nan", where, "x")));
  EXPECT_THROW(ParseInt("4.5", where, "n"), InputError);
}

TEST(TextReader, SplitsTokensAndFields) {
  const auto tokens = SplitTokens("  a \t b  c ");
  ASSERT_EQ(tokens.size(), 3u);
  EXPECT_EQ(tokens[2], "c");
  const auto fields = SplitFields("x,,y", ',');
  ASSERT_EQ(fields.size(), 3u);
  EXPECT_EQ(fields[1], "");
  EXPECT_EQ(Trim("  z \r\n"), "z");
}

TEST(TextReader, CountsLinesAndStripsCarriageReturns) {
  testing::TempDir dir;
  WriteFileAtomically(dir / "f.txt", "one\r\ntwo\n");
  TextReader reader(dir / "f.txt");
  EXPECT_EQ(*reader.NextLine(), "one");
  EXPECT_EQ(*reader.NextLine(), "two");
  EXPECT_EQ(reader.Where().line, 2);
  EXPECT_FALSE(reader.NextLine().has_value());
  EXPECT_THROW(TextReader(dir / "missing.txt"), InputError);
}

TEST(TextReader, ParseVectorChecksCount) {
  const SourceLocation where{"poses.txt", 9};
  const std::vector<std::string_view> three{"1", "2", "3"};
  EXPECT_TRUE(ParseVector<3>(three, where, "t").isApprox(Eigen::Vector3d(1, 2, 3)));
  EXPECT_THROW(ParseVector<4>(three, where, "q"), InputError);
}

}  // namespace
}  // namespace semslam
