// Segmentation model cards (models/*.yaml); only the parsing, no network is loaded.
#include <string>

#include "fuzz_input.h"
#include "semslam/semantics/model_card.h"

extern "C" int LLVMFuzzerTestOneInput(const std::uint8_t* data, size_t size) {
  const std::string text(semslam::fuzz::AsText(data, size));
  semslam::fuzz::ExpectOnlyInputErrors([&] {
    const semslam::ModelCard card = semslam::ParseModelCard(text, "/models", "card.yaml");
    card.Check();
    (void)card.ResolvedFormat();
  });
  return 0;
}
