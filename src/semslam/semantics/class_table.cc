#include "semslam/semantics/class_table.h"

#include <cctype>
#include <string>

namespace semslam {
namespace {

constexpr std::array<ClassInfo, kNumClasses> kClasses = {{
    {"road", {128, 64, 128}, false},
    {"sidewalk", {244, 35, 232}, false},
    {"building", {70, 70, 70}, false},
    {"wall", {102, 102, 156}, false},
    {"fence", {190, 153, 153}, false},
    {"pole", {153, 153, 153}, false},
    {"traffic light", {250, 170, 30}, false},
    {"traffic sign", {220, 220, 0}, false},
    {"vegetation", {107, 142, 35}, false},
    {"terrain", {152, 251, 152}, false},
    {"sky", {70, 130, 180}, false},
    {"person", {220, 20, 60}, true},
    {"rider", {255, 0, 0}, true},
    {"car", {0, 0, 142}, true},
    {"truck", {0, 0, 70}, true},
    {"bus", {0, 60, 100}, true},
    {"train", {0, 80, 100}, true},
    {"motorcycle", {0, 0, 230}, true},
    {"bicycle", {119, 11, 32}, true},
}};

constexpr std::array<std::string_view, kNumClasses> kKeys = {
    "road",         "sidewalk",   "building", "wall",       "fence",  "pole",  "traffic_light",
    "traffic_sign", "vegetation", "terrain",  "sky",        "person", "rider", "car",
    "truck",        "bus",        "train",    "motorcycle", "bicycle"};

// Cityscapes labelIds 0..33 in order (unlabeled, ego vehicle, rectification border, out of roi, static,
// dynamic, ground, road, sidewalk, parking, rail track, building, wall, fence, guard rail, bridge, tunnel,
// pole, polegroup, traffic light, traffic sign, vegetation, terrain, sky, person, rider, car, truck, bus,
// caravan, trailer, train, motorcycle, bicycle) and their trainIds.
constexpr std::array<std::uint8_t, 34> kLabelIdToTrainId = {
    255, 255, 255, 255, 255, 255, 255, 0,  1,  255, 255, 2,  3,   4,   255, 255, 255,
    5,   255, 6,   7,   8,   9,   10,  11, 12, 13,  14,  15, 255, 255, 16,  17,  18};

std::string Normalize(std::string_view name) {
  std::string out;
  for (char c : name) {
    if (c == '_' || c == ' ' || c == '-') continue;
    out.push_back(static_cast<char>(std::tolower(static_cast<unsigned char>(c))));
  }
  return out;
}

}  // namespace

const std::array<ClassInfo, kNumClasses>& ClassTable() { return kClasses; }

std::string_view ClassName(int train_id) {
  return IsValidTrainId(train_id) ? kClasses[static_cast<size_t>(train_id)].name : std::string_view("none");
}

std::string_view ClassKey(int train_id) {
  return IsValidTrainId(train_id) ? kKeys[static_cast<size_t>(train_id)] : std::string_view("none");
}

Rgb ClassColor(int train_id) {
  return IsValidTrainId(train_id) ? kClasses[static_cast<size_t>(train_id)].color : Rgb{0, 0, 0};
}

bool IsDynamicClass(int train_id) {
  return IsValidTrainId(train_id) && kClasses[static_cast<size_t>(train_id)].dynamic;
}

std::optional<int> TrainIdFromName(std::string_view name) {
  const std::string wanted = Normalize(name);
  for (int i = 0; i < kNumClasses; ++i) {
    if (Normalize(kClasses[static_cast<size_t>(i)].name) == wanted) return i;
  }
  return std::nullopt;
}

std::uint8_t LabelIdToTrainId(int label_id) {
  if (label_id < 0 || label_id >= static_cast<int>(kLabelIdToTrainId.size())) return kNoLabel;
  return kLabelIdToTrainId[static_cast<size_t>(label_id)];
}

const std::array<std::uint8_t, 256>& LabelIdToTrainIdTable() {
  static const std::array<std::uint8_t, 256> table = [] {
    std::array<std::uint8_t, 256> t{};
    for (int i = 0; i < 256; ++i) t[static_cast<size_t>(i)] = LabelIdToTrainId(i);
    return t;
  }();
  return table;
}

}  // namespace semslam
