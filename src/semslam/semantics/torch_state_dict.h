#pragma once
// PyTorch state dicts (.pth, .pt) read without PyTorch: the tensors of a saved `model.state_dict()`, by name.
// Two containers are read:
//  - the zip container (torch.save since PyTorch 1.6): entries <archive>/data.pkl (the pickled dict) and
//    <archive>/data/<key> (raw little-endian storages); entries must be stored uncompressed, as torch.save
//    writes them;
//  - the legacy container (before 1.6): five pickles in a row (magic number, protocol version, system
//    information, the dict, the list of storage keys), then every storage as an int64 element count followed
//    by its raw little-endian elements.
// In the dict, each tensor is torch._utils._rebuild_tensor_v2(storage, offset, size, stride, ...) with the
// storage a persistent id ('storage', torch.<Type>Storage, key, location, numel[, view]). Floating-point
// tensors (float, double, half) are returned as float, integer ones (long, int, short, char, byte, bool) as
// int64. Anything else throws InputError naming the file and what was found.

#include <cstdint>
#include <filesystem>
#include <map>
#include <string>
#include <string_view>
#include <vector>

namespace semslam {

struct TorchTensor {
  std::vector<std::int64_t> shape;  // empty for a scalar
  bool floating = true;
  std::vector<float> values;           // floating: row-major
  std::vector<std::int64_t> integers;  // integer tensors: row-major

  std::int64_t NumElements() const;
  std::string ShapeText() const;  // "32x3x3x3", "scalar"
};

class TorchStateDict {
 public:
  // Reads a .pth file. Throws InputError naming the file for anything it cannot read.
  static TorchStateDict Read(const std::filesystem::path& path);
  // The same from the file's bytes; `source` names it in errors.
  static TorchStateDict Parse(std::string_view bytes, const std::filesystem::path& source);

  const std::filesystem::path& source() const { return source_; }
  bool Contains(const std::string& name) const { return tensors_.count(name) != 0; }
  size_t size() const { return tensors_.size(); }
  std::vector<std::string> Names() const;
  // A tensor by name. Throws InputError naming the file and the tensor when it is missing, is not floating
  // point, or (when `shape` is given) has another shape.
  const TorchTensor& Get(const std::string& name, const std::vector<std::int64_t>& shape = {}) const;
  // Number of floating-point values over all tensors (the model's parameters and buffers).
  std::int64_t NumFloatValues() const;

 private:
  std::filesystem::path source_;
  std::map<std::string, TorchTensor> tensors_;
};

}  // namespace semslam
