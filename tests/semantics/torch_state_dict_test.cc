// PyTorch state dicts read without PyTorch: hand-made legacy and zip containers (strides, offsets, dtypes),
// the two published Cityscapes state dicts, and damaged input (truncation, bad CRC, compression, an opcode or
// a global outside the subset).

#include "semslam/semantics/torch_state_dict.h"

#include <gtest/gtest.h>

#include <array>
#include <cstring>
#include <fstream>
#include <string>
#include <vector>

#include "semslam/core/error.h"
#include "semslam/semantics/pickle_reader.h"
#include "support/test_support.h"

namespace semslam {
namespace {

std::string Le(std::uint64_t v, int n) {
  std::string s;
  for (int i = 0; i < n; ++i) s.push_back(static_cast<char>((v >> (8 * i)) & 0xFF));
  return s;
}

// Writes pickle opcodes the way torch.save does (protocol 2).
struct PickleWriter {
  std::string s = "\x80\x02";
  void Global(const std::string& module, const std::string& name) {
    s += 'c';
    s += module + "\n" + name + "\n";
  }
  void Str(const std::string& v) {
    s += 'X';
    s += Le(v.size(), 4);
    s += v;
  }
  void Int(std::int64_t v) {
    s += 'J';
    s += Le(static_cast<std::uint64_t>(v), 4);
  }
  void Mark() { s += "("; }
  void Tuple() { s += "t"; }
  void IntTuple(const std::vector<std::int64_t>& values) {
    Mark();
    for (auto v : values) Int(v);
    Tuple();
  }
  std::string Stop() { return s + "."; }
  // key -> torch._utils._rebuild_tensor_v2(storage, offset, size, stride, False, OrderedDict())
  void Tensor(const std::string& name, const std::string& storage_type, const std::string& key,
              std::int64_t numel, std::int64_t offset, const std::vector<std::int64_t>& size,
              const std::vector<std::int64_t>& stride) {
    Str(name);
    Global("torch._utils", "_rebuild_tensor_v2");
    Mark();
    Mark();
    Str("storage");
    Global("torch", storage_type);
    Str(key);
    Str("cpu");
    Int(numel);
    Tuple();
    s += "Q";  // BINPERSID
    Int(offset);
    IntTuple(size);
    IntTuple(stride);
    s += "\x89";  // False
    Global("collections", "OrderedDict");
    s += ")R";
    Tuple();
    s += "R";
  }
};

struct Storage {
  std::string key;
  std::string bytes;
  std::int64_t numel;
};

// A dict of: "w" = 2x3 float, the transpose of storage "0" (3x2) from element offset 1 of a 7-element
// storage; "h" = 2 halfs; "n" = a long scalar.
std::string TestDictPickle() {
  PickleWriter w;
  w.Global("collections", "OrderedDict");
  w.s += ")R";
  w.Mark();
  w.Tensor("w", "FloatStorage", "0", 7, 1, {2, 3}, {1, 2});
  w.Tensor("h", "HalfStorage", "1", 2, 0, {2}, {1});
  w.Tensor("n", "LongStorage", "2", 1, 0, {}, {});
  w.s += "u";  // SETITEMS
  return w.Stop();
}

std::vector<Storage> TestStorages() {
  std::string floats;
  for (int i = 0; i < 7; ++i) {
    const float v = static_cast<float>(i) * 1.5f;
    floats.append(reinterpret_cast<const char*>(&v), 4);
  }
  const std::string halfs = Le(0x3C00, 2) + Le(0xC100, 2);  // 1.0, -2.5
  return {{"0", floats, 7}, {"1", halfs, 2}, {"2", Le(static_cast<std::uint64_t>(-5), 8), 1}};
}

std::string LegacyFile() {
  std::string out;
  out +=
      std::string("\x80\x02\x8a\x0a", 4) + std::string("\x6c\xfc\x9c\x46\xf9\x20\x6a\xa8\x50\x19", 10) + ".";
  out += "\x80\x02M" + Le(1001, 2) + ".";
  out += "\x80\x02}X" + Le(13, 4) + "little_endian\x88s.";
  out += TestDictPickle();
  PickleWriter keys;
  keys.s += "]";
  keys.Mark();
  for (const Storage& s : TestStorages()) keys.Str(s.key);
  keys.s += "e";
  out += keys.Stop();
  for (const Storage& s : TestStorages()) out += Le(static_cast<std::uint64_t>(s.numel), 8) + s.bytes;
  return out;
}

std::uint32_t Crc(const std::string& bytes) {
  std::uint32_t crc = 0xFFFFFFFFu;
  for (unsigned char c : bytes) {
    crc ^= c;
    for (int k = 0; k < 8; ++k) crc = (crc & 1) ? 0xEDB88320u ^ (crc >> 1) : crc >> 1;
  }
  return crc ^ 0xFFFFFFFFu;
}

// A zip of stored entries, as torch.save writes (archive/data.pkl, archive/data/<key>, archive/version).
std::string ZipFile(const std::vector<std::pair<std::string, std::string>>& entries, int method = 0) {
  std::string out, directory;
  for (const auto& [name, data] : entries) {
    const std::string common = Le(20, 2) + Le(0, 2) + Le(static_cast<std::uint64_t>(method), 2) + Le(0, 4) +
                               Le(Crc(data), 4) + Le(data.size(), 4) + Le(data.size(), 4) +
                               Le(name.size(), 2) + Le(0, 2);
    directory += Le(0x02014b50, 4) + Le(20, 2) + common + Le(0, 2) + Le(0, 2) + Le(0, 2) + Le(0, 4) +
                 Le(out.size(), 4) + name;
    out += Le(0x04034b50, 4) + common + name + data;
  }
  const size_t directory_offset = out.size();
  out += directory;
  out += Le(0x06054b50, 4) + Le(0, 2) + Le(0, 2) + Le(entries.size(), 2) + Le(entries.size(), 2) +
         Le(directory.size(), 4) + Le(directory_offset, 4) + Le(0, 2);
  return out;
}

std::string TorchZip(int method = 0) {
  std::vector<std::pair<std::string, std::string>> entries = {{"archive/data.pkl", TestDictPickle()}};
  for (const Storage& s : TestStorages()) entries.emplace_back("archive/data/" + s.key, s.bytes);
  entries.emplace_back("archive/version", "3\n");
  return ZipFile(entries, method);
}

void ExpectTestDict(const TorchStateDict& dict) {
  ASSERT_EQ(dict.size(), 3u);
  const TorchTensor& w = dict.Get("w", {2, 3});
  // Element (i, j) is storage element 1 + i + 2 j: values 1.5 * that.
  EXPECT_EQ(w.values, (std::vector<float>{1.5f, 4.5f, 7.5f, 3.0f, 6.0f, 9.0f}));
  EXPECT_EQ(dict.Get("h", {2}).values, (std::vector<float>{1.0f, -2.5f}));
  EXPECT_EQ(dict.NumFloatValues(), 8);
  EXPECT_EQ(dict.Names(), (std::vector<std::string>{"h", "n", "w"}));
  // An integer tensor is not weights.
  EXPECT_THROW(dict.Get("n"), InputError);
}

// The message of the InputError that `f` throws ("" if none).
template <typename F>
std::string ErrorOf(F f) {
  try {
    f();
  } catch (const InputError& e) {
    return e.what();
  }
  return "";
}

TEST(TorchStateDict, ReadsTheLegacyContainer) {
  ExpectTestDict(TorchStateDict::Parse(LegacyFile(), "legacy.pth"));
}

TEST(TorchStateDict, ReadsTheZipContainer) { ExpectTestDict(TorchStateDict::Parse(TorchZip(), "new.pth")); }

TEST(TorchStateDict, NamesMissingTensorsAndWrongShapes) {
  const TorchStateDict dict = TorchStateDict::Parse(TorchZip(), "new.pth");
  EXPECT_NE(ErrorOf([&] { dict.Get("conv.weight"); }).find("tensor 'conv.weight' is missing"),
            std::string::npos);
  const std::string wrong = ErrorOf([&] { dict.Get("w", {3, 2}); });
  EXPECT_NE(wrong.find("new.pth"), std::string::npos) << wrong;
  EXPECT_NE(wrong.find("shape 2x3, expected 3x2"), std::string::npos) << wrong;
}

TEST(TorchStateDict, RejectsDamagedOrUnsupportedFiles) {
  // Every truncation of either container is an InputError naming the file, never a crash.
  for (const std::string& file : {LegacyFile(), TorchZip()}) {
    for (size_t n = 0; n < file.size(); n += 7) {
      const std::string message = ErrorOf([&] { TorchStateDict::Parse(file.substr(0, n), "cut.pth"); });
      EXPECT_NE(message.find("cut.pth"), std::string::npos) << "cut at " << n;
    }
  }
  // A flipped byte in a storage: the zip's CRC-32 catches it.
  std::string damaged = TorchZip();
  damaged[damaged.find("archive/data/0") + 14 + 5] ^= 0x40;
  EXPECT_NE(ErrorOf([&] { TorchStateDict::Parse(damaged, "d.pth"); }).find("CRC-32"), std::string::npos);
  // Deflated entries are not read.
  EXPECT_NE(ErrorOf([&] { TorchStateDict::Parse(TorchZip(8), "z.pth"); }).find("compressed"),
            std::string::npos);
  EXPECT_NE(ErrorOf([&] { TorchStateDict::Parse("hello", "t.pth"); }).find("not a PyTorch file"),
            std::string::npos);

  // An opcode outside the subset (NEWOBJ) and a global that is not part of a state dict.
  const auto with_pickle = [](const std::string& pickle) {
    return ZipFile({{"archive/data.pkl", pickle}, {"archive/version", "3\n"}});
  };
  const std::string newobj = ErrorOf([&] { TorchStateDict::Parse(with_pickle("\x80\x02\x81."), "o.pth"); });
  EXPECT_NE(newobj.find("unsupported pickle opcode 0x81"), std::string::npos) << newobj;
  EXPECT_NE(newobj.find("byte 2"), std::string::npos) << newobj;
  PickleWriter evil;
  evil.Global("os", "system");
  evil.Mark();
  evil.Str("true");
  evil.Tuple();
  evil.s += "R";
  const std::string global = ErrorOf([&] { TorchStateDict::Parse(with_pickle(evil.Stop()), "g.pth"); });
  EXPECT_NE(global.find("unsupported global os.system"), std::string::npos) << global;
  // A tensor reaching past its storage.
  PickleWriter big;
  big.Global("collections", "OrderedDict");
  big.s += ")R";
  big.Mark();
  big.Tensor("w", "FloatStorage", "0", 7, 5, {2, 3}, {3, 1});
  big.s += "u";
  const std::string past = ErrorOf([&] {
    TorchStateDict::Parse(
        ZipFile({{"archive/data.pkl", big.Stop()}, {"archive/data/0", std::string(28, '\0')}}), "p.pth");
  });
  EXPECT_NE(past.find("reaches element 10 of a storage of 7"), std::string::npos) << past;
}

TEST(TorchStateDict, ReadsThePublishedCityscapesWeights) {
  SEMSLAM_REQUIRE_SHARED_DATA(dir, "segmentation_weights");
  const TorchStateDict espnet = TorchStateDict::Read(dir / "espnetv2_s_2.0_city_1024x512.pth");
  EXPECT_EQ(espnet.size(), 526u);  // 459 float tensors + 67 batch counters
  EXPECT_EQ(espnet.Get("base_net.level1.conv.weight").shape, (std::vector<std::int64_t>{32, 3, 3, 3}));
  EXPECT_EQ(espnet.Get("bu_dec_l4.merge_layer.3.weight").shape, (std::vector<std::int64_t>{20, 10, 1, 1}));
  // 0.79 M parameters (the paper's figure) plus the batch norms' running statistics.
  EXPECT_EQ(espnet.NumFloatValues(), 814284);
  EXPECT_FLOAT_EQ(espnet.Get("base_net.level1.conv.weight").values[1], 0.2457660734653473f);
  const TorchStateDict sinet = TorchStateDict::Read(dir / "sinet_cityscapes.pth");
  EXPECT_EQ(sinet.size(), 629u);
  EXPECT_EQ(sinet.Get("classifier.weight").shape, (std::vector<std::int64_t>{19, 19, 2, 2}));
  EXPECT_EQ(sinet.NumFloatValues(), 128974);  // 0.12 M parameters + running statistics

  // Every truncation of a real file is an error naming it.
  std::ifstream in(dir / "sinet_cityscapes.pth", std::ios::binary);
  const std::string bytes((std::istreambuf_iterator<char>(in)), std::istreambuf_iterator<char>());
  for (size_t n : {size_t{0}, size_t{10}, size_t{200}, bytes.size() / 2, bytes.size() - 1}) {
    EXPECT_NE(ErrorOf([&] { TorchStateDict::Parse(bytes.substr(0, n), "sinet.pth"); }).find("sinet.pth"),
              std::string::npos)
        << n;
  }
}

}  // namespace
}  // namespace semslam
