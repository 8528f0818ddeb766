#include "semslam/core/utf8.h"

#include <gtest/gtest.h>

#include <string>

namespace semslam {
namespace {

TEST(Utf8, AcceptsWellFormedText) {
  EXPECT_TRUE(IsValidUtf8(""));
  EXPECT_TRUE(IsValidUtf8("Marienplatz"));
  EXPECT_TRUE(IsValidUtf8("Caf\xC3\xA9 M\xC3\xBCller"));     // é, ü
  EXPECT_TRUE(IsValidUtf8("\xE2\x82\xAC 5"));               // €
  EXPECT_TRUE(IsValidUtf8("\xF0\x9F\x9A\x97"));             // U+1F697
  EXPECT_TRUE(IsValidUtf8(std::string("a\0b", 3)));          // NUL is a code point
}

TEST(Utf8, FindsTheFirstBadByte) {
  EXPECT_EQ(FindInvalidUtf8("Caf\xE9"), 3u);                 // Latin-1 é
  EXPECT_EQ(FindInvalidUtf8("ab\xC3"), 2u);                  // truncated sequence
  EXPECT_EQ(FindInvalidUtf8("\xC0\xAF"), 0u);                // overlong '/'
  EXPECT_EQ(FindInvalidUtf8("\xE0\x80\xAF"), 0u);            // overlong
  EXPECT_EQ(FindInvalidUtf8("x\xED\xA0\x80"), 1u);           // surrogate U+D800
  EXPECT_EQ(FindInvalidUtf8("\xF4\x90\x80\x80"), 0u);        // above U+10FFFF
  EXPECT_EQ(FindInvalidUtf8("\xFF"), 0u);
  EXPECT_EQ(FindInvalidUtf8("ok\x80"), 2u);                  // lone continuation byte
}

TEST(Utf8, ErrorsNameWhereAndTheByte) {
  try {
    RequireUtf8("Caf\xE9", SourceLocation{"landmarks.csv", 3}, "name");
    FAIL();
  } catch (const InputError& e) {
    const std::string message = e.what();
    EXPECT_NE(message.find("landmarks.csv:3"), std::string::npos) << message;
    EXPECT_NE(message.find("0xE9"), std::string::npos) << message;
    EXPECT_TRUE(IsValidUtf8(message)) << "the message itself must be printable";
  }
  EXPECT_THROW(RequireUtf8Path("/data/s\xE9q", "--sequence"), InvalidArgument);
  EXPECT_NO_THROW(RequireUtf8Path("/data/s\xC3\xA9q", "--sequence"));
  try {
    RequireUtf8Path("/data/s\xE9q", "--sequence");
  } catch (const InvalidArgument& e) {
    EXPECT_TRUE(IsValidUtf8(e.what()));
    EXPECT_NE(std::string(e.what()).find("--sequence"), std::string::npos);
  }
}

}  // namespace
}  // namespace semslam
