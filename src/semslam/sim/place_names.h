#pragma once
// The names of the town's places (city.h's landmarks): buildings, and parks and squares. A town draws them
// without repetition.

#include <array>

namespace semslam::sim {

// A named place and the category the landmark catalogue gives it.
struct PlaceName {
  const char* name;
  const char* category;
};
inline constexpr std::array<PlaceName, 48> kBuildingNames = {{
    {"Town Hall", "townhall"},
    {"St. Mary's Church", "church"},
    {"Central Library", "library"},
    {"City Museum", "museum"},
    {"Main Station", "station"},
    {"St. Anne's Hospital", "hospital"},
    {"Market Hall", "market"},
    {"Grand Hotel", "hotel"},
    {"Old Theatre", "theatre"},
    {"Post Office", "post_office"},
    {"Fire Station", "fire_station"},
    {"Police Headquarters", "police"},
    {"Linden School", "school"},
    {"Savings Bank", "bank"},
    {"Court House", "court"},
    {"St. Peter's Church", "church"},
    {"Opera House", "theatre"},
    {"Science Centre", "museum"},
    {"Concert Hall", "theatre"},
    {"University Library", "library"},
    {"Clock Tower", "tower"},
    {"Swimming Hall", "sports"},
    {"Art Gallery", "museum"},
    {"Chamber of Commerce", "office"},
    {"Hotel Europa", "hotel"},
    {"Maple Primary School", "school"},
    {"St. Luke's Chapel", "church"},
    {"City Archive", "library"},
    {"Natural History Museum", "museum"},
    {"North Station", "station"},
    {"Children's Hospital", "hospital"},
    {"Fish Market", "market"},
    {"Cinema Palace", "theatre"},
    {"Old Customs House", "office"},
    {"Tax Office", "office"},
    {"Guild Hall", "townhall"},
    {"Music School", "school"},
    {"Sports Arena", "sports"},
    {"Observatory", "museum"},
    {"Old Brewery", "museum"},
    {"Trade Fair Hall", "market"},
    {"Registry Office", "office"},
    {"Water Tower", "tower"},
    {"Toy Museum", "museum"},
    {"Seamen's Church", "church"},
    {"Palace Hotel", "hotel"},
    {"Adult Education Centre", "school"},
    {"Bus Depot", "station"},
}};
inline constexpr std::array<PlaceName, 6> kOpenPlaceNames = {{
    {"Rose Park", "park"},
    {"Market Square", "square"},
    {"Chestnut Park", "park"},
    {"Fountain Square", "square"},
    {"Castle Gardens", "park"},
    {"Linden Green", "park"},
}};

}  // namespace semslam::sim
