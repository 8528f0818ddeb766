#include "semslam/semantics/torch_state_dict.h"

#include <array>
#include <cmath>
#include <cstring>
#include <fstream>
#include <iterator>
#include <optional>

#include "semslam/core/error.h"
#include "semslam/semantics/pickle_reader.h"

namespace semslam {
namespace {

using Kind = PickleValue::Kind;

// ---- little-endian helpers and CRC-32 (zip) ----

std::uint64_t ReadLe(std::string_view bytes, size_t at, int n) {
  std::uint64_t v = 0;
  for (int i = n - 1; i >= 0; --i)
    v = (v << 8) | static_cast<std::uint8_t>(bytes[at + static_cast<size_t>(i)]);
  return v;
}

std::uint32_t Crc32(std::string_view bytes) {
  static const std::array<std::uint32_t, 256> table = [] {
    std::array<std::uint32_t, 256> t{};
    for (std::uint32_t i = 0; i < 256; ++i) {
      std::uint32_t c = i;
      for (int k = 0; k < 8; ++k) c = (c & 1) ? 0xEDB88320u ^ (c >> 1) : c >> 1;
      t[i] = c;
    }
    return t;
  }();
  std::uint32_t crc = 0xFFFFFFFFu;
  for (char ch : bytes) crc = table[(crc ^ static_cast<std::uint8_t>(ch)) & 0xFF] ^ (crc >> 8);
  return crc ^ 0xFFFFFFFFu;
}

float HalfToFloat(std::uint16_t h) {
  const std::uint32_t sign = (h & 0x8000u) << 16;
  const int exponent = (h >> 10) & 0x1F;
  const std::uint32_t mantissa = h & 0x3FFu;
  float magnitude;
  if (exponent == 0) {
    magnitude = std::ldexp(static_cast<float>(mantissa), -24);
  } else if (exponent == 31) {
    magnitude = mantissa ? NAN : INFINITY;
  } else {
    magnitude = std::ldexp(static_cast<float>(mantissa | 0x400u), exponent - 25);
  }
  std::uint32_t bits;
  std::memcpy(&bits, &magnitude, 4);
  bits |= sign;
  float out;
  std::memcpy(&out, &bits, 4);
  return out;
}

// ---- storages ----

enum class DType { kFloat, kDouble, kHalf, kBFloat16, kLong, kInt, kShort, kChar, kByte, kBool };

struct DTypeInfo {
  const char* storage;  // the global's name
  DType dtype;
  int size;
};

constexpr DTypeInfo kDTypes[] = {
    {"torch.FloatStorage", DType::kFloat, 4}, {"torch.DoubleStorage", DType::kDouble, 8},
    {"torch.HalfStorage", DType::kHalf, 2},   {"torch.BFloat16Storage", DType::kBFloat16, 2},
    {"torch.LongStorage", DType::kLong, 8},   {"torch.IntStorage", DType::kInt, 4},
    {"torch.ShortStorage", DType::kShort, 2}, {"torch.CharStorage", DType::kChar, 1},
    {"torch.ByteStorage", DType::kByte, 1},   {"torch.BoolStorage", DType::kBool, 1},
};

bool IsFloating(DType t) {
  return t == DType::kFloat || t == DType::kDouble || t == DType::kHalf || t == DType::kBFloat16;
}

struct StorageRef {
  DTypeInfo type;
  std::string key;
  std::int64_t numel = 0;
  std::int64_t view_offset = 0;  // legacy views into a root storage
  std::string_view bytes;        // resolved once the container is read
};

struct TensorRef {
  size_t storage = 0;
  std::int64_t offset = 0;
  std::vector<std::int64_t> shape, stride;
};

class StateDictParser {
 public:
  explicit StateDictParser(const std::filesystem::path& source) : source_(source) {
    callbacks_.persistent_load = [this](const PickleValue& id) { return PersistentLoad(id); };
    callbacks_.reduce = [this](const std::string& global, const PickleValue& args) {
      return Reduce(global, args);
    };
  }

  [[noreturn]] void Fail(const std::string& message) const { throw InputError(source_, message); }

  PickleRef ReadOne(std::string_view bytes, size_t* offset) {
    return ReadPickle(bytes, offset, source_, callbacks_);
  }

  std::vector<StorageRef>& storages() { return storages_; }

  // The name -> tensor pairs of the pickled dict (a checkpoint's "state_dict" or "model" entry too).
  std::vector<std::pair<std::string, size_t>> Entries(const PickleValue& root) const {
    if (!root.Is(Kind::kDict)) Fail("the pickled object is a " + root.Describe() + ", not a state dict");
    std::vector<std::pair<std::string, size_t>> entries;
    for (const auto& [key, value] : root.dict) {
      if (key->Is(Kind::kString) && value->Is(Kind::kObject) && value->text == "tensor") {
        entries.emplace_back(key->text, static_cast<size_t>(value->integer));
      }
    }
    if (entries.empty()) {
      for (const auto& [key, value] : root.dict) {
        if (key->Is(Kind::kString) && (key->text == "state_dict" || key->text == "model") &&
            value->Is(Kind::kDict))
          return Entries(*value);
      }
      Fail("the pickled dict holds no tensors");
    }
    return entries;
  }

  TorchTensor Materialize(const std::string& name, size_t index) const {
    const TensorRef& ref = tensors_[index];
    const StorageRef& storage = storages_[ref.storage];
    if (storage.bytes.data() == nullptr)
      Fail("tensor '" + name + "': storage '" + storage.key + "' not found");
    // The highest element the strides reach must lie inside the storage.
    std::int64_t count = 1, last = ref.offset + storage.view_offset;
    for (size_t d = 0; d < ref.shape.size(); ++d) {
      if (ref.shape[d] < 0 || ref.stride[d] < 0) Fail("tensor '" + name + "': negative size or stride");
      count *= ref.shape[d];
      if (ref.shape[d] > 0) last += (ref.shape[d] - 1) * ref.stride[d];
    }
    const std::int64_t available = static_cast<std::int64_t>(storage.bytes.size()) / storage.type.size;
    if (count > 0 && (last >= available || ref.offset < 0)) {
      Fail("tensor '" + name + "' reaches element " + std::to_string(last) + " of a storage of " +
           std::to_string(available));
    }
    TorchTensor t;
    t.shape = ref.shape;
    t.floating = IsFloating(storage.type.dtype);
    if (t.floating) {
      t.values.resize(static_cast<size_t>(count));
    } else {
      t.integers.resize(static_cast<size_t>(count));
    }
    std::vector<std::int64_t> index_nd(ref.shape.size(), 0);
    std::int64_t element = ref.offset + storage.view_offset;
    for (std::int64_t i = 0; i < count; ++i) {
      const size_t at = static_cast<size_t>(element) * static_cast<size_t>(storage.type.size);
      const std::uint64_t raw = ReadLe(storage.bytes, at, storage.type.size);
      if (t.floating) {
        float v = 0.0f;
        if (storage.type.dtype == DType::kFloat) {
          const auto bits = static_cast<std::uint32_t>(raw);
          std::memcpy(&v, &bits, 4);
        } else if (storage.type.dtype == DType::kDouble) {
          double d;
          std::memcpy(&d, &raw, 8);
          v = static_cast<float>(d);
        } else if (storage.type.dtype == DType::kHalf) {
          v = HalfToFloat(static_cast<std::uint16_t>(raw));
        } else {
          const auto bits = static_cast<std::uint32_t>(raw) << 16;
          std::memcpy(&v, &bits, 4);
        }
        t.values[static_cast<size_t>(i)] = v;
      } else {
        std::int64_t v = static_cast<std::int64_t>(raw);
        const int bits = 8 * storage.type.size;
        if (storage.type.dtype != DType::kByte && storage.type.dtype != DType::kBool && bits < 64 &&
            (raw >> (bits - 1)) & 1)
          v -= std::int64_t{1} << bits;  // sign-extend
        t.integers[static_cast<size_t>(i)] = v;
      }
      // Next element in row-major order.
      for (size_t d = ref.shape.size(); d-- > 0;) {
        element += ref.stride[d];
        if (++index_nd[d] < ref.shape[d]) break;
        element -= ref.stride[d] * ref.shape[d];
        index_nd[d] = 0;
      }
    }
    return t;
  }

 private:
  static std::optional<std::int64_t> Int(const PickleValue& v) {
    if (v.Is(Kind::kInt)) return v.integer;
    return std::nullopt;
  }
  std::vector<std::int64_t> IntTuple(const PickleValue& v, const char* what) const {
    if (!v.Is(Kind::kTuple) && !v.Is(Kind::kList))
      Fail(std::string("tensor ") + what + " is a " + v.Describe());
    std::vector<std::int64_t> out;
    for (const PickleRef& item : v.items) {
      const auto i = Int(*item);
      if (!i) Fail(std::string("tensor ") + what + " holds a " + item->Describe());
      out.push_back(*i);
    }
    return out;
  }

  PickleRef PersistentLoad(const PickleValue& id) {
    // ('storage', torch.FloatStorage, key, location, numel[, view_metadata])
    if (!id.Is(Kind::kTuple) || id.items.size() < 5 || !id.items[0]->Is(Kind::kString) ||
        id.items[0]->text != "storage")
      Fail("persistent id " + id.Describe() + " is not a tensor storage");
    const PickleValue& type = *id.items[1];
    const PickleValue& key = *id.items[2];
    const auto numel = Int(*id.items[4]);
    if (!type.Is(Kind::kGlobal)) Fail("storage type is a " + type.Describe());
    StorageRef ref;
    bool known = false;
    for (const DTypeInfo& info : kDTypes) {
      if (type.text == info.storage) {
        ref.type = info;
        known = true;
      }
    }
    if (!known) Fail("unsupported storage type " + type.text);
    if (!key.Is(Kind::kString)) Fail("storage key is a " + key.Describe());
    if (!numel || *numel < 0) Fail("storage '" + key.text + "' has no valid element count");
    ref.key = key.text;
    ref.numel = *numel;
    if (id.items.size() >= 6 && id.items[5]->Is(Kind::kTuple)) {
      // Legacy view: (view_key, offset, view_size) into the root storage `key`.
      const PickleValue& view = *id.items[5];
      const auto offset = view.items.size() == 3 ? Int(*view.items[1]) : std::nullopt;
      if (!offset || *offset < 0) Fail("storage view of '" + key.text + "' is malformed");
      ref.view_offset = *offset;
    }
    storages_.push_back(ref);
    auto object = MakePickleValue(Kind::kObject);
    object->text = "storage";
    object->integer = static_cast<std::int64_t>(storages_.size() - 1);
    return object;
  }

  PickleRef Reduce(const std::string& global, const PickleValue& args) {
    if (global == "collections.OrderedDict") {
      auto dict = MakePickleValue(Kind::kDict);
      if (!args.items.empty() && args.items[0]->Is(Kind::kList)) {
        for (const PickleRef& pair : args.items[0]->items) {
          if (!pair->Is(Kind::kTuple) || pair->items.size() != 2) Fail("OrderedDict from a malformed list");
          dict->dict.emplace_back(pair->items[0], pair->items[1]);
        }
      }
      return dict;
    }
    if (global == "torch._utils._rebuild_tensor_v2" || global == "torch._utils._rebuild_tensor") {
      if (args.items.size() < 4) Fail(global + " with " + args.Describe());
      const PickleValue& storage = *args.items[0];
      if (!storage.Is(Kind::kObject) || storage.text != "storage")
        Fail(global + " of a " + storage.Describe() + " instead of a storage");
      const auto offset = Int(*args.items[1]);
      if (!offset) Fail("tensor offset is a " + args.items[1]->Describe());
      TensorRef ref;
      ref.storage = static_cast<size_t>(storage.integer);
      ref.offset = *offset;
      ref.shape = IntTuple(*args.items[2], "size");
      ref.stride = IntTuple(*args.items[3], "stride");
      if (ref.shape.size() != ref.stride.size()) Fail("tensor size and stride differ in length");
      tensors_.push_back(std::move(ref));
      auto object = MakePickleValue(Kind::kObject);
      object->text = "tensor";
      object->integer = static_cast<std::int64_t>(tensors_.size() - 1);
      return object;
    }
    if (global == "torch._utils._rebuild_parameter") {
      // (data, requires_grad, backward_hooks): the tensor itself.
      if (args.items.empty()) Fail(global + " without arguments");
      return args.items[0];
    }
    return nullptr;
  }

  const std::filesystem::path& source_;
  PickleCallbacks callbacks_;
  std::vector<StorageRef> storages_;
  std::vector<TensorRef> tensors_;
};

// ---- containers ----

struct ZipEntry {
  std::string name;
  std::string_view data;
};

std::vector<ZipEntry> ReadZipEntries(std::string_view bytes, const std::filesystem::path& source) {
  const auto fail = [&](const std::string& m) { throw InputError(source, "zip container: " + m); };
  // The end-of-central-directory record: 22 bytes plus a comment of at most 65535.
  if (bytes.size() < 22) fail("truncated (no end-of-central-directory record)");
  size_t eocd = std::string_view::npos;
  const size_t lowest = bytes.size() > 22 + 65535 ? bytes.size() - 22 - 65535 : 0;
  for (size_t at = bytes.size() - 22 + 1; at-- > lowest;) {
    if (ReadLe(bytes, at, 4) == 0x06054b50u) {
      eocd = at;
      break;
    }
  }
  if (eocd == std::string_view::npos) fail("truncated or damaged (no end-of-central-directory record)");
  const auto count = ReadLe(bytes, eocd + 10, 2);
  const auto directory_size = ReadLe(bytes, eocd + 12, 4);
  const auto directory_offset = ReadLe(bytes, eocd + 16, 4);
  if (count == 0xFFFF || directory_offset == 0xFFFFFFFFu) fail("zip64 archives are not supported");
  if (directory_offset + directory_size > eocd) fail("central directory outside the file");
  std::vector<ZipEntry> entries;
  size_t at = static_cast<size_t>(directory_offset);
  for (std::uint64_t i = 0; i < count; ++i) {
    if (at + 46 > eocd || ReadLe(bytes, at, 4) != 0x02014b50u) fail("damaged central directory entry");
    const auto method = ReadLe(bytes, at + 10, 2);
    const auto crc = static_cast<std::uint32_t>(ReadLe(bytes, at + 16, 4));
    const auto compressed = ReadLe(bytes, at + 20, 4);
    const auto size = ReadLe(bytes, at + 24, 4);
    const auto name_length = ReadLe(bytes, at + 28, 2);
    const auto extra_length = ReadLe(bytes, at + 30, 2);
    const auto comment_length = ReadLe(bytes, at + 32, 2);
    const auto local = ReadLe(bytes, at + 42, 4);
    if (at + 46 + name_length > eocd) fail("damaged central directory entry");
    ZipEntry entry;
    entry.name = std::string(bytes.substr(at + 46, name_length));
    at += 46 + name_length + extra_length + comment_length;
    if (method != 0) {
      fail("entry '" + entry.name + "' is compressed (method " + std::to_string(method) +
           "); only stored entries are read, as torch.save writes them");
    }
    if (compressed != size || size == 0xFFFFFFFFu) fail("entry '" + entry.name + "' has inconsistent sizes");
    if (local + 30 > bytes.size() || ReadLe(bytes, local, 4) != 0x04034b50u)
      fail("entry '" + entry.name + "': damaged local header");
    const size_t data =
        static_cast<size_t>(local + 30 + ReadLe(bytes, local + 26, 2) + ReadLe(bytes, local + 28, 2));
    if (data + size > bytes.size()) fail("entry '" + entry.name + "' is truncated");
    entry.data = bytes.substr(data, static_cast<size_t>(size));
    if (Crc32(entry.data) != crc) fail("entry '" + entry.name + "' is damaged (CRC-32 mismatch)");
    entries.push_back(std::move(entry));
  }
  return entries;
}

}  // namespace

std::int64_t TorchTensor::NumElements() const {
  std::int64_t n = 1;
  for (std::int64_t d : shape) n *= d;
  return n;
}

std::string TorchTensor::ShapeText() const {
  if (shape.empty()) return "scalar";
  std::string s;
  for (std::int64_t d : shape) {
    if (!s.empty()) s += 'x';
    s += std::to_string(d);
  }
  return s;
}

TorchStateDict TorchStateDict::Read(const std::filesystem::path& path) {
  std::ifstream in(path, std::ios::binary);
  if (!in) throw InputError(path, "cannot open the PyTorch weights file");
  const std::string bytes((std::istreambuf_iterator<char>(in)), std::istreambuf_iterator<char>());
  if (in.bad()) throw InputError(path, "cannot read the PyTorch weights file");
  return Parse(bytes, path);
}

TorchStateDict TorchStateDict::Parse(std::string_view bytes, const std::filesystem::path& source) {
  StateDictParser parser(source);
  PickleRef root;
  if (bytes.size() >= 4 && bytes.substr(0, 4) == std::string_view("PK\x03\x04", 4)) {
    const std::vector<ZipEntry> entries = ReadZipEntries(bytes, source);
    const ZipEntry* pickle = nullptr;
    for (const ZipEntry& e : entries) {
      const std::string suffix = "data.pkl";
      if (e.name.size() >= suffix.size() &&
          e.name.compare(e.name.size() - suffix.size(), suffix.size(), suffix) == 0 &&
          (e.name.size() == suffix.size() || e.name[e.name.size() - suffix.size() - 1] == '/'))
        pickle = &e;
      if (e.name.size() >= 9 && e.name.compare(e.name.size() - 9, 9, "byteorder") == 0 && e.data != "little")
        parser.Fail("zip container: tensors stored " + std::string(e.data) + "-endian are not supported");
    }
    if (pickle == nullptr) parser.Fail("zip container without data.pkl: not a PyTorch file");
    size_t offset = 0;
    root = parser.ReadOne(pickle->data, &offset);
    const std::string prefix = pickle->name.substr(0, pickle->name.size() - 8) + "data/";
    for (StorageRef& s : parser.storages()) {
      for (const ZipEntry& e : entries) {
        if (e.name == prefix + s.key) s.bytes = e.data;
      }
      if (s.bytes.data() == nullptr)
        parser.Fail("zip container: storage entry '" + prefix + s.key + "' is missing");
    }
  } else if (!bytes.empty() && static_cast<std::uint8_t>(bytes[0]) == 0x80) {
    // Legacy: magic number, protocol version, system information, the dict, the storage keys, the storages.
    size_t offset = 0;
    const PickleRef magic = parser.ReadOne(bytes, &offset);
    static const std::string kMagic("\x6c\xfc\x9c\x46\xf9\x20\x6a\xa8\x50\x19", 10);
    if (!magic->Is(Kind::kBigInt) || magic->text != kMagic)
      parser.Fail("not a PyTorch file (the first pickle is not PyTorch's magic number)");
    const PickleRef version = parser.ReadOne(bytes, &offset);
    if (!version->Is(Kind::kInt) || version->integer != 1001)
      parser.Fail("unsupported legacy PyTorch protocol version " + version->Describe());
    const PickleRef info = parser.ReadOne(bytes, &offset);
    if (info->Is(Kind::kDict)) {
      for (const auto& [key, value] : info->dict) {
        if (key->Is(Kind::kString) && key->text == "little_endian" && value->Is(Kind::kBool) &&
            !value->integer)
          parser.Fail("tensors stored big-endian are not supported");
      }
    }
    root = parser.ReadOne(bytes, &offset);
    const PickleRef keys = parser.ReadOne(bytes, &offset);
    if (!keys->Is(Kind::kList))
      parser.Fail("legacy container: the storage key list is a " + keys->Describe());
    for (const PickleRef& key : keys->items) {
      if (!key->Is(Kind::kString)) parser.Fail("legacy container: a storage key is a " + key->Describe());
      if (offset + 8 > bytes.size()) parser.Fail("truncated: storage '" + key->text + "' is missing");
      const auto numel = ReadLe(bytes, offset, 8);
      offset += 8;
      // The storage's element size comes from its type in the dict (the header only counts elements).
      int element_size = 0;
      for (StorageRef& s : parser.storages()) {
        if (s.key != key->text) continue;
        element_size = s.type.size;
      }
      if (element_size == 0)
        parser.Fail("legacy container: storage '" + key->text + "' is not used by any tensor");
      if (numel > (bytes.size() - offset) / static_cast<std::uint64_t>(element_size))
        parser.Fail("truncated: storage '" + key->text + "' holds " + std::to_string(numel) +
                    " elements, the file ends first");
      const std::string_view data =
          bytes.substr(offset, static_cast<size_t>(numel) * static_cast<size_t>(element_size));
      offset += data.size();
      for (StorageRef& s : parser.storages()) {
        if (s.key != key->text) continue;
        if (s.view_offset == 0 && static_cast<std::uint64_t>(s.numel) != numel)
          parser.Fail("storage '" + key->text + "' holds " + std::to_string(numel) +
                      " elements, the dict says " + std::to_string(s.numel));
        s.bytes = data;
      }
    }
    if (offset != bytes.size())
      parser.Fail("legacy container: " + std::to_string(bytes.size() - offset) +
                  " bytes after the last storage");
  } else {
    throw InputError(source, "not a PyTorch file (neither a zip container nor a legacy pickle)");
  }
  TorchStateDict dict;
  dict.source_ = source;
  for (const auto& [name, index] : parser.Entries(*root))
    dict.tensors_[name] = parser.Materialize(name, index);
  return dict;
}

std::vector<std::string> TorchStateDict::Names() const {
  std::vector<std::string> names;
  for (const auto& [name, tensor] : tensors_) names.push_back(name);
  return names;
}

const TorchTensor& TorchStateDict::Get(const std::string& name,
                                       const std::vector<std::int64_t>& shape) const {
  const auto it = tensors_.find(name);
  if (it == tensors_.end())
    throw InputError(source_, "tensor '" + name + "' is missing: not the expected network");
  const TorchTensor& t = it->second;
  if (!t.floating) throw InputError(source_, "tensor '" + name + "' is not floating point");
  if (!shape.empty() && t.shape != shape) {
    TorchTensor expected;
    expected.shape = shape;
    throw InputError(source_, "tensor '" + name + "' has shape " + t.ShapeText() + ", expected " +
                                  expected.ShapeText() + ": not the expected network");
  }
  return t;
}

std::int64_t TorchStateDict::NumFloatValues() const {
  std::int64_t n = 0;
  for (const auto& [name, t] : tensors_) n += t.floating ? t.NumElements() : 0;
  return n;
}

}  // namespace semslam
