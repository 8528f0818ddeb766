#pragma once
// The synthetic town: a Manhattan-like street grid with blocks of buildings, sidewalks, street furniture,
// vegetation and parked cars, as a list of simple primitives (axis-aligned boxes, vertical cylinders,
// ellipsoids) over an analytic ground plane (the road, z = 0).
//
// Town frame: x east, y north, z up, metres; it is the ENU frame of the WGS84 origin (enu_from_town = I).
// Everything is generated from CityOptions alone: the same options give the same town, bit for bit.

#include <Eigen/Core>
#include <cstdint>
#include <string>
#include <vector>

namespace semslam::sim {

enum class Shape : std::uint8_t { kBox, kCylinder, kEllipsoid };

// What a surface looks like (the textures are in texture.h).
enum class Material : std::uint8_t {
  kSidewalk,      // paving tiles on top, curb stone on the sides
  kFacade,        // building walls with windows, doors, shop signs (style = facade style index)
  kRoof,          // flat roof tops (also used for the top of a facade box)
  kWall,          // stone / concrete garden walls
  kFence,         // slatted fences
  kFoliage,       // tree crowns, bushes, hedges
  kBark,          // tree trunks
  kGrass,         // lawns and terrain patches
  kPole,          // lamp posts, sign posts
  kLamp,          // lamp heads
  kTrafficLight,  // housing with three lamps facing the road
  kSign,          // sign plates
  kCarBody,
  kCarCabin,  // windows band
  kTire,
  kClothes,
  kSkin,
  kBicycle,
};

struct Primitive {
  Shape shape = Shape::kBox;
  Material material = Material::kSidewalk;
  std::uint8_t label = 0;  // Cityscapes trainId of the surface
  std::uint8_t facing =
      0;  // for signs and traffic lights: the axis/sign the face looks along (0..3: +x,+y,-x,-y)
  std::uint32_t object = 0;                      // index into City::objects
  Eigen::Vector3f lo = Eigen::Vector3f::Zero();  // axis-aligned bounds; a cylinder is vertical and inscribed,
  Eigen::Vector3f hi = Eigen::Vector3f::Zero();  // an ellipsoid inscribed (centre and radii from the bounds)
  float tone = 0.5f;                             // per-object brightness variation in [0, 1]
  std::uint32_t variant = 0;                     // per-object random bits for textures
  std::uint16_t style = 0;                       // facade style index (kFacade)
};

// How one building's walls look.
struct FacadeStyle {
  float wall_grey = 150;  // base brightness of the wall (0..255)
  bool brick = false;     // brick courses; otherwise plaster with panels
  float floor_height = 3.2f;
  float window_period = 3.0f;  // horizontal distance between window columns
  float window_width = 1.3f;
  float window_height = 1.6f;
  float sill_height = 0.9f;  // window bottom above the floor
  float frame_width = 0.09f;
  float frame_grey = 210;
  float glass_grey = 45;
  bool shop_front = false;  // ground floor: shop windows and a sign band
  float sign_grey = 230;
  float plinth_height = 0.5f;  // darker base course
};

struct CityObject {
  std::string kind;  // "building", "tree", "car", "pole", "traffic_light", "traffic_sign", "sidewalk", ...
  std::uint8_t label = 0;
  std::string name;  // landmarks only
};

// A named building or place (landmarks.csv). Position: footprint centroid at ground level (town frame).
struct Place {
  std::string name;
  std::string category;  // townhall, church, library, park, museum, ...
  Eigen::Vector3d position = Eigen::Vector3d::Zero();
  std::uint32_t object = 0;
};

// Street centre lines x = xs[i] (running north-south) and y = ys[j] (east-west). Intersection (i, j) has id
// j * xs.size() + i. Segments join neighbouring intersections.
struct StreetGrid {
  std::vector<double> xs, ys;
  double road_half_width = 6.0;  // centre line to curb
  double sidewalk_width = 4.0;
  double lane_offset = 1.8;    // centre line to the centre of the driving lane
  double parking_inner = 3.7;  // the parking strip spans [parking_inner, road_half_width] from the centre

  struct Segment {
    int id = 0;
    int a = 0, b = 0;  // intersection ids, a < b
    double length = 0;
  };
  std::vector<Segment> segments;

  int ni() const { return static_cast<int>(xs.size()); }
  int nj() const { return static_cast<int>(ys.size()); }
  int IntersectionId(int i, int j) const { return j * ni() + i; }
  int I(int id) const { return id % ni(); }
  int J(int id) const { return id / ni(); }
  Eigen::Vector2d Position(int id) const {
    return {xs[static_cast<size_t>(I(id))], ys[static_cast<size_t>(J(id))]};
  }
  // Whether the route may use the intersection: the border streets are not driven.
  bool Drivable(int i, int j) const { return i >= 1 && j >= 1 && i <= ni() - 2 && j <= nj() - 2; }
  // The segment joining two neighbouring intersections, or -1.
  int SegmentBetween(int a, int b) const;
};

struct CityOptions {
  std::uint64_t seed = 1;
  std::uint64_t traffic_seed = 0;  // parked cars, persons, bicycles; 0: derived from seed
  int blocks_x = 8;                // blocks between the border streets
  int blocks_y = 8;
  double min_block = 60.0;  // street spacing, metres (centre line to centre line)
  double max_block = 120.0;
  double parked_car_density = 0.55;  // fraction of the free parking strip taken by cars
  double person_density = 0.01;      // persons per metre of sidewalk
  double bicycle_density = 0.006;
  double tree_density = 0.6;  // fraction of streets lined with trees
  int park_blocks = 2;        // blocks that become parks or squares
  // Throws InvalidArgument naming the bad field.
  void Check() const;
};

struct City {
  CityOptions options;
  StreetGrid grid;
  std::vector<Primitive> primitives;
  std::vector<CityObject> objects;
  std::vector<FacadeStyle> styles;
  std::vector<Place> places;  // every named place of the town (landmarks.csv lists those along the route)
  Eigen::Vector2d min_corner = Eigen::Vector2d::Zero();  // bounds of all geometry (xy)
  Eigen::Vector2d max_corner = Eigen::Vector2d::Zero();
  float max_height = 0;  // highest primitive top
};

City GenerateCity(const CityOptions& options);

}  // namespace semslam::sim
