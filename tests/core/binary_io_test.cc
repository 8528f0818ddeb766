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

// A payload of several chunks, streamed: the same file as one written whole, and never whole in the writer.
TEST(BinaryIo, StreamedChecksummedFileIsTheFileWrittenWhole) {
  testing::TempDir dir;
  const std::string_view magic("TESTFIL\0", 8);
  BinaryWriter whole;
  {
    ChecksummedFileWriter streamed(dir / "streamed.bin", magic, 4);
    size_t most_buffered = 0;
    for (std::uint32_t i = 0; i < 700000; ++i) {  // 2.8 MB of values, then a string and a vector
      whole.Put(i);
      streamed.payload().Put(i);
      most_buffered = std::max(most_buffered, streamed.payload().bytes().size());
    }
    whole.PutString("the end");
    streamed.payload().PutString("the end");
    whole.PutVector(std::vector<double>{1.5, -2.0});
    streamed.payload().PutVector(std::vector<double>{1.5, -2.0});
    EXPECT_LE(most_buffered, size_t{1} << 20) << "the writer held more than a chunk";
    EXPECT_FALSE(std::filesystem::exists(dir / "streamed.bin")) << "nothing is in place before Commit()";
    streamed.Commit();
  }
  WriteChecksummedFile(dir / "whole.bin", magic, 4, whole.bytes());
  EXPECT_EQ(testing::ReadText(dir / "streamed.bin"), testing::ReadText(dir / "whole.bin"));
  const ChecksummedFile read = ReadChecksummedFile(dir / "streamed.bin", magic);
  EXPECT_EQ(read.version, 4u);
  EXPECT_EQ(read.payload, whole.bytes());

  // Dropped without Commit(): no file, no temporary left.
  {
    ChecksummedFileWriter dropped(dir / "dropped.bin", magic, 4);
    dropped.payload().Put(1);
  }
  const auto entries = std::distance(std::filesystem::directory_iterator(dir.path()), {});
  EXPECT_EQ(entries, 2) << "streamed.bin and whole.bin alone";
}

TEST(BinaryIo, AnEmptyFileIsCalledEmpty) {
  testing::TempDir dir;
  std::ofstream(dir / "empty.bin").close();
  try {
    ReadChecksummedFile(dir / "empty.bin", std::string_view("TESTFIL\0", 8));
    FAIL();
  } catch (const InputError& e) {
    EXPECT_NE(std::string(e.what()).find("empty.bin: the file is empty"), std::string::npos) << e.what();
  }
}

TEST(BinaryIo, ReadingADirectoryAsAChecksummedFileNamesIt) {
  testing::TempDir dir;
  try {
    ReadChecksummedFile(dir.path(), std::string_view("TESTFIL\0", 8));
    FAIL();
  } catch (const InputError& e) {
    EXPECT_NE(std::string(e.what()).find(dir.path().string()), std::string::npos) << e.what();
  }
}

}  // namespace
}  // namespace semslam
