#include <gtest/gtest.h>

#include <fstream>
#include <sstream>

#include "semslam/core/error.h"
#include "semslam/place/vocabulary.h"
#include "support/test_support.h"

namespace semslam {
namespace {

// 32 descriptor bytes as DBoW2 writes them: decimal, space separated.
std::string Bytes(int first, int rest) {
  std::ostringstream s;
  s << first;
  for (int i = 1; i < 32; ++i) s << ' ' << rest;
  return s.str();
}

// k = 2, L = 2: root -> {1: zeros, 2: ones}; 1 -> {3, 4}; 2 -> {5, 6}. Nodes listed depth first, as a
// DBoW2 file may be, to check the renumbering.
std::string TinyDbow2() {
  std::ostringstream s;
  s << "2 2  0 0\n";
  s << "0 0 " << Bytes(0, 0) << " 0\n";       // 1
  s << "1 1 " << Bytes(0, 0) << " 0.5\n";     // 2: leaf under 1 (word 0 in the file)
  s << "1 1 " << Bytes(255, 0) << " 1\n";     // 3: leaf under 1
  s << "0 0 " << Bytes(255, 255) << " 0\n";   // 4
  s << "4 1 " << Bytes(255, 255) << " 2\n";   // 5: leaf under 4
  s << "4 1 " << Bytes(0, 255) << " 0.75\n";  // 6: leaf under 4
  s << "\n";
  return s.str();
}

std::filesystem::path Write(const testing::TempDir& dir, const std::string& name, const std::string& text) {
  const auto path = dir / name;
  std::ofstream(path) << text;
  return path;
}

Descriptor FromBytes(int first, int rest) {
  Descriptor d{};
  auto* bytes = reinterpret_cast<std::uint8_t*>(d.data());
  bytes[0] = static_cast<std::uint8_t>(first);
  for (int i = 1; i < 32; ++i) bytes[i] = static_cast<std::uint8_t>(rest);
  return d;
}

TEST(Dbow2Text, ParsesAHandWrittenVocabulary) {
  testing::TempDir dir;
  const auto path = Write(dir, "tiny.txt", TinyDbow2());
  const Vocabulary v = Vocabulary::LoadDbow2Text(path);
  EXPECT_EQ(v.branching(), 2);
  EXPECT_EQ(v.depth(), 2);
  EXPECT_EQ(v.size(), 4u);
  EXPECT_EQ(v.num_nodes(), 7u);
  EXPECT_EQ(v.weighting(), BowWeighting::kTfIdf);
  EXPECT_EQ(v.descriptor_pattern(), OrbDescriptorPattern::kOpenCv);
  // Bytes are OpenCV's descriptor bytes in order: byte 0 is the low byte of word 0.
  EXPECT_EQ(FromBytes(255, 0)[0], 0xFFu);
  EXPECT_EQ(v.WordWeight(v.Word(FromBytes(0, 0))), 0.5);
  EXPECT_EQ(v.WordWeight(v.Word(FromBytes(255, 0))), 1.0);
  EXPECT_EQ(v.WordWeight(v.Word(FromBytes(255, 255))), 2.0);
  EXPECT_EQ(v.WordWeight(v.Word(FromBytes(0, 255))), 0.75);
  EXPECT_EQ(v.WordWeight(v.Word(FromBytes(250, 255))), 2.0);  // nearest: the ones
  // Breadth-first renumbering: node 1 and 2 are the root's children, then their children.
  EXPECT_EQ(v.Parent(1), 0u);
  EXPECT_EQ(v.Parent(2), 0u);
  EXPECT_EQ(v.Parent(3), 1u);
  EXPECT_EQ(v.Parent(6), 2u);
  // Load() recognizes the format; converting to ours and back is exact.
  EXPECT_EQ(Vocabulary::Load(path), v);
  v.Save(dir / "tiny.voc");
  EXPECT_EQ(Vocabulary::Load(dir / "tiny.voc"), v);
}

void ExpectError(const std::string& text, const std::string& fragment) {
  testing::TempDir dir;
  const auto path = Write(dir, "bad.txt", text);
  try {
    Vocabulary::LoadDbow2Text(path);
    ADD_FAILURE() << "no error for: " << fragment;
  } catch (const InputError& e) {
    EXPECT_NE(std::string(e.what()).find(fragment), std::string::npos) << e.what();
    EXPECT_NE(std::string(e.what()).find("bad.txt"), std::string::npos) << e.what();
  }
}

TEST(Dbow2Text, MalformedFilesGiveLocatedErrors) {
  ExpectError("", "empty");
  ExpectError("2 2 0\n", "header");
  ExpectError("1 2 0 0\n0 1 " + Bytes(0, 0) + " 1\n", "k");
  ExpectError("2 2 0 x\n", "weighting");
  ExpectError("2 2 0 0\n0 1 " + Bytes(0, 0) + "\n", "expected 35 fields");
  ExpectError("2 2 0 0\n0 1 " + Bytes(0, 0) + " 1\n3 1 " + Bytes(0, 0) + " 1\n", "parent");
  ExpectError("2 2 0 0\n0 1 " + Bytes(300, 0) + " 1\n", "[0, 255]");
  ExpectError("2 2 0 0\n0 1 " + Bytes(0, 0) + " -1\n", "weight");
  ExpectError("2 2 0 0\n0 1 " + Bytes(0, 0) + " nan\n", "weight");
  ExpectError("2 2 0 0\n0 1 " + Bytes(0, 0) + " 1\n1 1 " + Bytes(0, 0) + " 1\n", "is a leaf");
  ExpectError("2 2 0 0\n0 0 " + Bytes(0, 0) + " 0\n", "not a leaf but has no children");
  ExpectError("2 1 0 0\n0 0 " + Bytes(0, 0) + " 0\n1 1 " + Bytes(0, 0) + " 1\n", "deeper than L");
  ExpectError("2 2 0 0\n", "no nodes");
  // The error names the line.
  ExpectError("2 2 0 0\n0 1 " + Bytes(0, 0) + " 1\n0 1 " + Bytes(0, 0) + " oops\n", ":3");
}

}  // namespace
}  // namespace semslam
