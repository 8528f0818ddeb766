#include "semslam/core/binary_io.h"

#include <gtest/gtest.h>

#include <fstream>

#include "semslam/core/atomic_file.h"
#include "support/test_support.h"

namespace semslam {
namespace {

TEST(BinaryIo, RoundTripsValuesVectorsAndStrings) {
  BinaryWriter w;
  w.Put<std::uint32_t>(7);
  w.Put<double>(-2.5);
  w.PutVector(std::vector<float>{1.f, 2.f, 3.f});
  w.PutString("hello");
  BinaryReader r(w.bytes(), "mem");
  EXPECT_EQ(r.Get<std::uint32_t>(), 7u);
  EXPECT_EQ(r.Get<double>(), -2.5);
  EXPECT_EQ(r.GetVector<float>(), (std::vector<float>{1.f, 2.f, 3.f}));
  EXPECT_EQ(r.GetString(), "hello");
  EXPECT_TRUE(r.AtEnd());
  EXPECT_THROW(r.Get<std::uint8_t>(), InputError);
}

TEST(BinaryIo, ChecksummedFileDetectsCorruptionAndTruncation) {
  testing::TempDir dir;
  const auto path = dir / "x.bin";
  WriteChecksummedFile(path, std::string_view("TESTFIL\0", 8), 3, "payload bytes");
  const ChecksummedFile f = ReadChecksummedFile(path, std::string_view("TESTFIL\0", 8));
  EXPECT_EQ(f.version, 3u);
  EXPECT_EQ(f.payload, "payload bytes");
  EXPECT_THROW(ReadChecksummedFile(path, std::string_view("OTHERFI\0", 8)), InputError);

  std::string bytes;
  {
    std::ifstream in(path, std::ios::binary);
    bytes.assign(std::istreambuf_iterator<char>(in), {});
  }
  std::string corrupt = bytes;
  corrupt.back() ^= 0x01;
  WriteFileAtomically(path, corrupt);
  try {
    ReadChecksummedFile(path, std::string_view("TESTFIL\0", 8));
    FAIL();
  } catch (const InputError& e) {
    EXPECT_NE(std::string(e.what()).find("checksum"), std::string::npos);
  }
  WriteFileAtomically(path, bytes.substr(0, bytes.size() - 3));
  EXPECT_THROW(ReadChecksummedFile(path, std::string_view("TESTFIL\0", 8)), InputError);
}

}  // namespace
}  // namespace semslam
