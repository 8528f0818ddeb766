#include "semslam/semantics/torch_networks.h"

namespace semslam {

const TorchArchitecture* FindTorchArchitecture(const std::string& name) {
  static const TorchArchitecture kArchitectures[] = {
      {"espnetv2", 16, 1, &BuildEspNetV2},
      {"sinet", 128, 2, &BuildSiNet},
  };
  for (const TorchArchitecture& a : kArchitectures) {
    if (a.name == name) return &a;
  }
  return nullptr;
}

std::vector<std::string> TorchArchitectureNames() { return {"espnetv2", "sinet"}; }

}  // namespace semslam
