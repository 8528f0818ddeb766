#include "semslam/semantics/pickle_reader.h"

#include <cstring>
#include <unordered_map>

#include "semslam/core/error.h"

namespace semslam {
namespace {

// The opcodes of the subset (Python's Lib/pickletools.py documents every one).
enum Op : std::uint8_t {
  kMark = '(',
  kStop = '.',
  kNone = 'N',
  kNewTrue = 0x88,
  kNewFalse = 0x89,
  kBinInt = 'J',
  kBinInt1 = 'K',
  kBinInt2 = 'M',
  kLong1 = 0x8a,
  kBinFloat = 'G',
  kBinUnicode = 'X',
  kShortBinUnicode = 0x8c,
  kBinUnicode8 = 0x8d,
  kBinString = 'T',
  kShortBinString = 'U',
  kBinBytes = 'B',
  kShortBinBytes = 'C',
  kEmptyTuple = ')',
  kTuple = 't',
  kTuple1 = 0x85,
  kTuple2 = 0x86,
  kTuple3 = 0x87,
  kEmptyList = ']',
  kAppend = 'a',
  kAppends = 'e',
  kList = 'l',
  kEmptyDict = '}',
  kSetItem = 's',
  kSetItems = 'u',
  kDict = 'd',
  kBinPut = 'q',
  kLongBinPut = 'r',
  kMemoize = 0x94,
  kBinGet = 'h',
  kLongBinGet = 'j',
  kGlobal = 'c',
  kStackGlobal = 0x93,
  kReduce = 'R',
  kBuild = 'b',
  kBinPersId = 'Q',
  kProto = 0x80,
  kFrame = 0x95,
};

class Unpickler {
 public:
  Unpickler(std::string_view bytes, size_t offset, const std::filesystem::path& source,
            const PickleCallbacks& callbacks)
      : bytes_(bytes), offset_(offset), source_(source), callbacks_(callbacks) {}

  PickleRef Run(size_t* end_offset) {
    for (;;) {
      op_offset_ = offset_;
      const std::uint8_t op = Byte();
      switch (op) {
        case kProto: {
          const std::uint8_t version = Byte();
          if (version < 2 || version > 4)
            Fail("pickle protocol " + std::to_string(version) + " is not supported");
          break;
        }
        case kFrame:
          Take(8);  // a frame length: the frame's opcodes follow inline
          break;
        case kStop: {
          if (stack_.size() != 1 || !marks_.empty()) Fail("the pickle does not end with exactly one value");
          *end_offset = offset_;
          return stack_.back();
        }
        case kMark:
          marks_.push_back(stack_.size());
          break;
        case kNone:
          Push(MakePickleValue(PickleValue::Kind::kNone));
          break;
        case kNewTrue:
        case kNewFalse: {
          auto v = MakePickleValue(PickleValue::Kind::kBool);
          v->integer = op == kNewTrue ? 1 : 0;
          Push(v);
          break;
        }
        case kBinInt:
          PushInt(static_cast<std::int32_t>(Unsigned(4)));
          break;
        case kBinInt1:
          PushInt(Byte());
          break;
        case kBinInt2:
          PushInt(static_cast<std::int64_t>(Unsigned(2)));
          break;
        case kLong1:
          PushLong(Byte());
          break;
        case kBinFloat: {
          // Big-endian IEEE 754 double.
          const std::string_view raw = Take(8);
          std::uint64_t bits = 0;
          for (char c : raw) bits = (bits << 8) | static_cast<std::uint8_t>(c);
          auto v = MakePickleValue(PickleValue::Kind::kFloat);
          std::memcpy(&v->real, &bits, sizeof(double));
          Push(v);
          break;
        }
        case kBinUnicode:
        case kBinString:
        case kBinBytes:
          PushString(Take(Unsigned(4)));
          break;
        case kShortBinUnicode:
        case kShortBinString:
        case kShortBinBytes:
          PushString(Take(Byte()));
          break;
        case kBinUnicode8:
          PushString(Take(Unsigned(8)));
          break;
        case kEmptyTuple:
          Push(MakePickleValue(PickleValue::Kind::kTuple));
          break;
        case kTuple: {
          auto v = MakePickleValue(PickleValue::Kind::kTuple);
          v->items = PopToMark();
          Push(v);
          break;
        }
        case kTuple1:
        case kTuple2:
        case kTuple3: {
          const size_t n = static_cast<size_t>(op - kTuple1 + 1);
          Need(n);
          auto v = MakePickleValue(PickleValue::Kind::kTuple);
          v->items.assign(stack_.end() - static_cast<std::ptrdiff_t>(n), stack_.end());
          stack_.resize(stack_.size() - n);
          Push(v);
          break;
        }
        case kEmptyList:
          Push(MakePickleValue(PickleValue::Kind::kList));
          break;
        case kList: {
          auto v = MakePickleValue(PickleValue::Kind::kList);
          v->items = PopToMark();
          Push(v);
          break;
        }
        case kAppend: {
          PickleRef item = Pop();
          Top(PickleValue::Kind::kList, "APPEND").items.push_back(std::move(item));
          break;
        }
        case kAppends: {
          std::vector<PickleRef> items = PopToMark();
          auto& list = Top(PickleValue::Kind::kList, "APPENDS").items;
          list.insert(list.end(), items.begin(), items.end());
          break;
        }
        case kEmptyDict:
          Push(MakePickleValue(PickleValue::Kind::kDict));
          break;
        case kDict: {
          auto v = MakePickleValue(PickleValue::Kind::kDict);
          AddPairs(*v, PopToMark());
          Push(v);
          break;
        }
        case kSetItem: {
          PickleRef value = Pop();
          PickleRef key = Pop();
          Top(PickleValue::Kind::kDict, "SETITEM").dict.emplace_back(std::move(key), std::move(value));
          break;
        }
        case kSetItems: {
          std::vector<PickleRef> items = PopToMark();
          AddPairs(Top(PickleValue::Kind::kDict, "SETITEMS"), items);
          break;
        }
        case kBinPut:
          Memoize(Byte());
          break;
        case kLongBinPut:
          Memoize(Unsigned(4));
          break;
        case kMemoize:
          Memoize(memo_.size());
          break;
        case kBinGet:
          Recall(Byte());
          break;
        case kLongBinGet:
          Recall(Unsigned(4));
          break;
        case kGlobal: {
          const std::string module = Line();
          const std::string name = Line();
          PushGlobal(module + "." + name);
          break;
        }
        case kStackGlobal: {
          PickleRef name = Pop();
          PickleRef module = Pop();
          if (!module->Is(PickleValue::Kind::kString) || !name->Is(PickleValue::Kind::kString))
            Fail("STACK_GLOBAL needs two strings");
          PushGlobal(module->text + "." + name->text);
          break;
        }
        case kReduce: {
          PickleRef arguments = Pop();
          PickleRef callable = Pop();
          if (!callable->Is(PickleValue::Kind::kGlobal)) Fail("REDUCE of " + callable->Describe());
          if (!arguments->Is(PickleValue::Kind::kTuple)) Fail("REDUCE with " + arguments->Describe());
          PickleRef result = callbacks_.reduce ? callbacks_.reduce(callable->text, *arguments) : nullptr;
          if (!result) Fail("unsupported global " + callable->text + " (not part of a PyTorch state dict)");
          Push(std::move(result));
          break;
        }
        case kBuild:
          // The state of an object (an OrderedDict's _metadata attribute, say): not needed for the tensors.
          Pop();
          Need(1);
          break;
        case kBinPersId: {
          PickleRef id = Pop();
          PickleRef object = callbacks_.persistent_load ? callbacks_.persistent_load(*id) : nullptr;
          if (!object) Fail("unknown persistent id " + id->Describe());
          Push(std::move(object));
          break;
        }
        default: {
          static const char* const kHex = "0123456789abcdef";
          std::string hex = "0x";
          hex += kHex[op >> 4];
          hex += kHex[op & 15];
          Fail("unsupported pickle opcode " + hex + " (a PyTorch state dict does not use it)");
        }
      }
    }
  }

 private:
  [[noreturn]] void Fail(const std::string& message) const {
    throw InputError(source_, "pickle at byte " + std::to_string(op_offset_) + ": " + message);
  }
  std::string_view Take(std::uint64_t n) {
    if (n > bytes_.size() - offset_) Fail("truncated (the file ends inside a pickle)");
    const std::string_view s = bytes_.substr(offset_, static_cast<size_t>(n));
    offset_ += static_cast<size_t>(n);
    return s;
  }
  std::uint8_t Byte() { return static_cast<std::uint8_t>(Take(1)[0]); }
  std::uint64_t Unsigned(int n) {
    const std::string_view raw = Take(static_cast<std::uint64_t>(n));
    std::uint64_t v = 0;
    for (int i = n - 1; i >= 0; --i) v = (v << 8) | static_cast<std::uint8_t>(raw[static_cast<size_t>(i)]);
    return v;
  }
  std::string Line() {
    const size_t end = bytes_.find('\n', offset_);
    if (end == std::string_view::npos || end - offset_ > 256) Fail("truncated or overlong GLOBAL name");
    std::string s(bytes_.substr(offset_, end - offset_));
    offset_ = end + 1;
    return s;
  }

  void Push(PickleRef v) {
    if (stack_.size() > kMaxStack) Fail("stack deeper than " + std::to_string(kMaxStack));
    stack_.push_back(std::move(v));
  }
  void PushInt(std::int64_t i) {
    auto v = MakePickleValue(PickleValue::Kind::kInt);
    v->integer = i;
    Push(v);
  }
  void PushLong(size_t n) {
    const std::string_view raw = Take(n);
    if (n <= 8) {
      std::uint64_t bits = 0;
      for (size_t i = n; i-- > 0;) bits = (bits << 8) | static_cast<std::uint8_t>(raw[i]);
      // Sign-extend from the top byte.
      if (n > 0 && n < 8 && (static_cast<std::uint8_t>(raw[n - 1]) & 0x80))
        bits |= ~std::uint64_t{0} << (8 * n);
      PushInt(static_cast<std::int64_t>(bits));
      return;
    }
    auto v = MakePickleValue(PickleValue::Kind::kBigInt);
    v->text = std::string(raw);
    Push(v);
  }
  void PushString(std::string_view s) {
    auto v = MakePickleValue(PickleValue::Kind::kString);
    v->text = std::string(s);
    Push(v);
  }
  void PushGlobal(std::string name) {
    auto v = MakePickleValue(PickleValue::Kind::kGlobal);
    v->text = std::move(name);
    Push(v);
  }
  void Need(size_t n) const {
    const size_t floor = marks_.empty() ? 0 : marks_.back();
    if (stack_.size() < floor + n) Fail("stack underflow");
  }
  PickleRef Pop() {
    Need(1);
    PickleRef v = std::move(stack_.back());
    stack_.pop_back();
    return v;
  }
  PickleValue& Top(PickleValue::Kind kind, const char* op) {
    Need(1);
    if (!stack_.back()->Is(kind)) Fail(std::string(op) + " on " + stack_.back()->Describe());
    return *stack_.back();
  }
  std::vector<PickleRef> PopToMark() {
    if (marks_.empty()) Fail("no MARK on the stack");
    const size_t mark = marks_.back();
    marks_.pop_back();
    std::vector<PickleRef> items(stack_.begin() + static_cast<std::ptrdiff_t>(mark), stack_.end());
    stack_.resize(mark);
    return items;
  }
  void AddPairs(PickleValue& dict, const std::vector<PickleRef>& items) {
    if (items.size() % 2 != 0) Fail("odd number of items for a dict");
    for (size_t i = 0; i < items.size(); i += 2) dict.dict.emplace_back(items[i], items[i + 1]);
  }
  void Memoize(std::uint64_t index) {
    if (stack_.empty()) Fail("memo PUT with an empty stack");
    memo_[index] = stack_.back();
  }
  void Recall(std::uint64_t index) {
    const auto it = memo_.find(index);
    if (it == memo_.end()) Fail("memo GET of unknown index " + std::to_string(index));
    Push(it->second);
  }

  static constexpr size_t kMaxStack = 1 << 20;
  std::string_view bytes_;
  size_t offset_;
  size_t op_offset_ = 0;
  const std::filesystem::path& source_;
  const PickleCallbacks& callbacks_;
  std::vector<PickleRef> stack_;
  std::vector<size_t> marks_;
  std::unordered_map<std::uint64_t, PickleRef> memo_;
};

}  // namespace

PickleRef MakePickleValue(PickleValue::Kind kind) {
  auto v = std::make_shared<PickleValue>();
  v->kind = kind;
  return v;
}

std::string PickleValue::Describe() const {
  switch (kind) {
    case Kind::kNone:
      return "None";
    case Kind::kBool:
      return integer ? "True" : "False";
    case Kind::kInt:
      return "integer " + std::to_string(integer);
    case Kind::kBigInt:
      return "integer of " + std::to_string(text.size()) + " bytes";
    case Kind::kFloat:
      return "float " + std::to_string(real);
    case Kind::kString:
      return "string '" + (text.size() > 40 ? text.substr(0, 40) + "..." : text) + "'";
    case Kind::kTuple:
      return "tuple of " + std::to_string(items.size());
    case Kind::kList:
      return "list of " + std::to_string(items.size());
    case Kind::kDict:
      return "dict of " + std::to_string(dict.size());
    case Kind::kGlobal:
      return "global " + text;
    case Kind::kObject:
      return text;
  }
  return "?";
}

PickleRef ReadPickle(std::string_view bytes, size_t* offset, const std::filesystem::path& source,
                     const PickleCallbacks& callbacks) {
  Require(offset != nullptr && *offset <= bytes.size(), "ReadPickle: offset outside the bytes");
  Unpickler unpickler(bytes, *offset, source, callbacks);
  return unpickler.Run(offset);
}

}  // namespace semslam
