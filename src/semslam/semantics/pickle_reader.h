#pragma once
// A reader of the subset of Python's pickle format (protocols 2-4) that PyTorch writes for a state dict:
// integers, floats, strings, tuples, lists, dicts, None/True/False, memo references, globals applied with
// REDUCE, BUILD, and persistent ids (PyTorch's references to tensor storages). Nothing is ever executed: a
// global is only a name, and REDUCE asks the caller what a call of that name stands for. Anything else (an
// opcode outside the subset, a truncated stream, a stack underflow) throws InputError naming the file and
// the byte offset.

#include <cstdint>
#include <filesystem>
#include <functional>
#include <memory>
#include <string>
#include <string_view>
#include <utility>
#include <vector>

namespace semslam {

struct PickleValue;
using PickleRef = std::shared_ptr<PickleValue>;

struct PickleValue {
  enum class Kind {
    kNone,
    kBool,
    kInt,
    kBigInt,  // an integer beyond 64 bits (LONG1): its little-endian two's-complement bytes in `text`
    kFloat,
    kString,  // text and byte strings alike
    kTuple,
    kList,
    kDict,    // ordered; OrderedDict too
    kGlobal,  // "module.name"
    kObject,  // what a REDUCE or a persistent id stood for, as the caller built it (tag + index)
  };
  Kind kind = Kind::kNone;
  std::int64_t integer = 0;  // kBool, kInt; kObject: the caller's index
  double real = 0.0;
  std::string text;                                   // kString, kGlobal; kObject: the caller's tag
  std::vector<PickleRef> items;                       // kTuple, kList
  std::vector<std::pair<PickleRef, PickleRef>> dict;  // kDict

  bool Is(Kind k) const { return kind == k; }
  // Short description for error messages ("tuple of 6", "string 'storage'", "global torch.FloatStorage").
  std::string Describe() const;
};

PickleRef MakePickleValue(PickleValue::Kind kind);

struct PickleCallbacks {
  // REDUCE of a global with its argument tuple: returns what the call stands for, or null when the global is
  // not supported (the reader then throws an InputError naming it).
  std::function<PickleRef(const std::string& global, const PickleValue& arguments)> reduce;
  // A persistent id (BINPERSID): returns the object it refers to. Throws (or returns null) when unknown.
  std::function<PickleRef(const PickleValue& persistent_id)> persistent_load;
};

// Reads one pickle from `bytes` starting at `*offset` and leaves `*offset` just past its STOP opcode.
// `source` names the file in errors. Throws InputError.
PickleRef ReadPickle(std::string_view bytes, size_t* offset, const std::filesystem::path& source,
                     const PickleCallbacks& callbacks);

}  // namespace semslam
