#pragma once
// The 19 Cityscapes evaluation classes (trainIds 0..18), in one place: names, palette colours, which classes
// move (kept out of tracking when asked), and the mapping from Cityscapes labelIds (0..33) to trainIds.

#include <array>
#include <cstdint>
#include <optional>
#include <string_view>

namespace semslam {

inline constexpr int kNumClasses = 19;
// "No class": unlabeled pixels, ignored ground truth, points without a label.
inline constexpr std::uint8_t kNoLabel = 255;

enum class SemanticClass : std::uint8_t {
  kRoad = 0,
  kSidewalk = 1,
  kBuilding = 2,
  kWall = 3,
  kFence = 4,
  kPole = 5,
  kTrafficLight = 6,
  kTrafficSign = 7,
  kVegetation = 8,
  kTerrain = 9,
  kSky = 10,
  kPerson = 11,
  kRider = 12,
  kCar = 13,
  kTruck = 14,
  kBus = 15,
  kTrain = 16,
  kMotorcycle = 17,
  kBicycle = 18,
};

constexpr int TrainId(SemanticClass c) { return static_cast<int>(c); }

struct Rgb {
  std::uint8_t r = 0, g = 0, b = 0;
  friend bool operator==(const Rgb&, const Rgb&) = default;
};

struct ClassInfo {
  std::string_view name;  // lower case, words separated by spaces ("traffic light")
  Rgb color;              // Cityscapes palette
  bool dynamic;           // person, rider and vehicles: may move between observations
};

// Indexed by trainId.
const std::array<ClassInfo, kNumClasses>& ClassTable();

inline bool IsValidTrainId(int id) { return id >= 0 && id < kNumClasses; }
// The class name, or "none" for kNoLabel and anything out of range.
std::string_view ClassName(int train_id);
// The palette colour; black for kNoLabel and anything out of range.
Rgb ClassColor(int train_id);
// Whether the class can move (person, rider, car, truck, bus, train, motorcycle, bicycle). False for
// kNoLabel.
bool IsDynamicClass(int train_id);
// trainId of a class name: case-insensitive, '_' or ' ' or nothing between words ("traffic_light",
// "TrafficLight"). nullopt when unknown.
std::optional<int> TrainIdFromName(std::string_view name);
// A name usable as a JSON key or file name: "traffic_light".
std::string_view ClassKey(int train_id);

// Cityscapes labelId (0..33, and -1 for the licence plate) -> trainId, kNoLabel for classes not evaluated
// (ego vehicle, parking, rail track, guard rail, caravan, ...) and for anything out of range.
std::uint8_t LabelIdToTrainId(int label_id);
// The 256-entry lookup table of LabelIdToTrainId for 8-bit label images (255 stays 255).
const std::array<std::uint8_t, 256>& LabelIdToTrainIdTable();

}  // namespace semslam
