#include "semslam/sim/city.h"

#include <algorithm>
#include <array>
#include <cmath>
#include <string>

#include "semslam/core/error.h"
#include "semslam/semantics/class_table.h"
#include "semslam/sim/city_parts.h"
#include "semslam/sim/place_names.h"
#include "semslam/sim/random.h"

namespace semslam::sim {
namespace {

using city_parts::AddBicycle;
using city_parts::AddBush;
using city_parts::AddCar;
using city_parts::AddPerson;
using city_parts::AddTrafficLight;
using city_parts::AddTrafficSign;
using city_parts::AddTree;
using city_parts::Bits;
using city_parts::Builder;
using city_parts::DrawLook;
using city_parts::F;
using city_parts::kSidewalkHeight;
using city_parts::Look;

constexpr float kGrassTop = 0.19f;  // a lawn's top, above the sidewalk

FacadeStyle RandomStyle(Rng& rng) {
  FacadeStyle s;
  s.brick = rng.Bernoulli(0.4);
  s.wall_grey = F(s.brick ? rng.Uniform(85, 150) : rng.Uniform(120, 215));
  s.floor_height = F(rng.Uniform(2.9, 3.6));
  s.window_period = F(rng.Uniform(2.3, 4.0));
  s.window_width = F(rng.Uniform(0.9, std::min(1.9, s.window_period - 0.6)));
  s.window_height = F(rng.Uniform(1.2, s.floor_height - 1.1));
  s.sill_height = F(rng.Uniform(0.7, s.floor_height - s.window_height - 0.3));
  s.frame_width = F(rng.Uniform(0.06, 0.14));
  s.frame_grey = F(s.wall_grey > 175 ? rng.Uniform(50, 110) : rng.Uniform(190, 240));
  s.glass_grey = F(rng.Uniform(25, 75));
  s.shop_front = rng.Bernoulli(0.35);
  s.sign_grey = F(rng.Bernoulli(0.5) ? rng.Uniform(200, 245) : rng.Uniform(20, 60));
  s.plinth_height = F(rng.Uniform(0.3, 0.8));
  return s;
}

// A side of a block: the building line runs along `axis` (0: x, 1: y) at `front` on the other axis; the
// street lies on the `outward` side (+1 or -1 along the other axis).
struct Frontage {
  int axis = 0;
  double front = 0;
  int outward = 1;
  double a0 = 0, a1 = 0;  // extent along the axis
};

class CityGenerator {
 public:
  explicit CityGenerator(const CityOptions& options) : options_(options), b_(city_) {
    city_.options = options;
  }

  City Run() {
    Rng grid_rng = Rng::Stream(options_.seed, 1);
    MakeGrid(grid_rng);
    MakeBlocks();
    MakeStreetFurniture();
    MakeTraffic();
    Finish();
    return std::move(city_);
  }

 private:
  void MakeGrid(Rng& rng) {
    StreetGrid& g = city_.grid;
    auto lines = [&](int blocks) {
      std::vector<double> v{0.0};
      for (int k = 0; k < blocks; ++k)
        v.push_back(v.back() + rng.Uniform(options_.min_block, options_.max_block));
      const double mid = v.back() / 2;
      for (double& x : v) x = std::round((x - mid) * 10.0) / 10.0;
      return v;
    };
    g.xs = lines(options_.blocks_x);
    g.ys = lines(options_.blocks_y);
    int id = 0;
    for (int j = 0; j < g.nj(); ++j) {
      for (int i = 0; i < g.ni(); ++i) {
        if (i + 1 < g.ni()) {
          g.segments.push_back({id++, g.IntersectionId(i, j), g.IntersectionId(i + 1, j),
                                g.xs[static_cast<size_t>(i + 1)] - g.xs[static_cast<size_t>(i)]});
        }
        if (j + 1 < g.nj()) {
          g.segments.push_back({id++, g.IntersectionId(i, j), g.IntersectionId(i, j + 1),
                                g.ys[static_cast<size_t>(j + 1)] - g.ys[static_cast<size_t>(j)]});
        }
      }
    }
  }

  // Blocks between the street lines, and a band of buildings beyond the border streets.
  void MakeBlocks() {
    const StreetGrid& g = city_.grid;
    constexpr double kBand = 40.0;
    std::vector<double> ex{g.xs.front() - kBand - g.road_half_width};
    ex.insert(ex.end(), g.xs.begin(), g.xs.end());
    ex.push_back(g.xs.back() + kBand + g.road_half_width);
    std::vector<double> ey{g.ys.front() - kBand - g.road_half_width};
    ey.insert(ey.end(), g.ys.begin(), g.ys.end());
    ey.push_back(g.ys.back() + kBand + g.road_half_width);
    const int nbx = static_cast<int>(ex.size()) - 1;
    const int nby = static_cast<int>(ey.size()) - 1;

    // Which inner blocks become parks or squares, and which hold a named building.
    Rng plan = Rng::Stream(options_.seed, 2);
    std::vector<int> inner;
    for (int bj = 1; bj < nby - 1; ++bj) {
      for (int bi = 1; bi < nbx - 1; ++bi) inner.push_back(bj * nbx + bi);
    }
    for (size_t k = inner.size(); k > 1; --k)
      std::swap(inner[k - 1], inner[static_cast<size_t>(plan.UniformInt(0, static_cast<int>(k) - 1))]);
    const int parks = std::min<int>(options_.park_blocks, static_cast<int>(kOpenPlaceNames.size()));
    std::vector<int> kind(static_cast<size_t>(nbx * nby), 0);  // 0 normal, 1 open place, 2 named building
    size_t next = 0;
    for (int k = 0; k < parks && next < inner.size(); ++k) kind[static_cast<size_t>(inner[next++])] = 1;
    building_names_.assign(kBuildingNames.begin(), kBuildingNames.end());
    for (size_t k = building_names_.size(); k > 1; --k) {
      std::swap(building_names_[k - 1],
                building_names_[static_cast<size_t>(plan.UniformInt(0, static_cast<int>(k) - 1))]);
    }
    for (int named = 0; next < inner.size() && named < static_cast<int>(building_names_.size()); ++next) {
      if (plan.Bernoulli(0.75)) {
        kind[static_cast<size_t>(inner[next])] = 2;
        ++named;
      }
    }

    for (int bj = 0; bj < nby; ++bj) {
      for (int bi = 0; bi < nbx; ++bi) {
        Rng rng = Rng::Stream(options_.seed,
                              Hash3(3, static_cast<std::uint64_t>(bi), static_cast<std::uint64_t>(bj)));
        const double x0 = ex[static_cast<size_t>(bi)] + g.road_half_width;
        const double x1 = ex[static_cast<size_t>(bi + 1)] - g.road_half_width;
        const double y0 = ey[static_cast<size_t>(bj)] + g.road_half_width;
        const double y1 = ey[static_cast<size_t>(bj + 1)] - g.road_half_width;
        const bool real_w = bi > 0, real_e = bi<nbx - 1, real_s = bj> 0, real_n = bj < nby - 1;
        if (!real_w && !real_e) continue;
        if (!real_s && !real_n) continue;
        const std::uint32_t slab = b_.NewObject("sidewalk", SemanticClass::kSidewalk);
        const Look slab_look = DrawLook(rng);
        b_.Box(slab, Material::kSidewalk, SemanticClass::kSidewalk, {F(x0), F(y0), 0.f},
               {F(x1), F(y1), kSidewalkHeight}, slab_look.tone, slab_look.variant);
        const int k = kind[static_cast<size_t>(bj * nbx + bi)];
        if (k == 1) {
          OpenPlace(rng, x0, y0, x1, y1);
          continue;
        }
        const double sw = g.sidewalk_width;
        const double corner = 16.0;
        std::vector<Frontage> sides;
        if (real_s) sides.push_back({0, y0 + sw, -1, x0 + sw, x1 - sw});
        if (real_n) sides.push_back({0, y1 - sw, +1, x0 + sw, x1 - sw});
        if (real_w)
          sides.push_back(
              {1, x0 + sw, -1, y0 + sw + (real_s ? corner : 0.0), y1 - sw - (real_n ? corner : 0.0)});
        if (real_e)
          sides.push_back(
              {1, x1 - sw, +1, y0 + sw + (real_s ? corner : 0.0), y1 - sw - (real_n ? corner : 0.0)});
        // Depth available behind each building line: half the block.
        const double max_depth = std::max(6.0, 0.5 * std::min(x1 - x0, y1 - y0) - sw - 1.0);
        int landmark_side = k == 2 ? rng.UniformInt(0, static_cast<int>(sides.size()) - 1) : -1;
        for (size_t s = 0; s < sides.size(); ++s) {
          Lots(rng, sides[s], std::min(max_depth, 18.0), static_cast<int>(s) == landmark_side);
        }
        // The back yards: lawn with a few trees, mostly hidden.
        const double inset = sw + std::min(max_depth, 18.0) + 1.0;
        if (x1 - x0 > 2 * inset + 4 && y1 - y0 > 2 * inset + 4) {
          const std::uint32_t yard = b_.NewObject("terrain", SemanticClass::kTerrain);
          const Look yard_look = DrawLook(rng);
          b_.Box(yard, Material::kGrass, SemanticClass::kTerrain,
                 {F(x0 + inset), F(y0 + inset), kSidewalkHeight}, {F(x1 - inset), F(y1 - inset), kGrassTop},
                 yard_look.tone, yard_look.variant);
        }
      }
    }
  }

  // A building line cut into lots: buildings mostly, some gaps with walls, fences and gardens.
  void Lots(Rng& rng, const Frontage& f, double max_depth, bool landmark) {
    double a = f.a0;
    bool placed_landmark = !landmark;
    while (f.a1 - a > 4.0) {
      double width = rng.Uniform(9.0, 24.0);
      if (!placed_landmark) width = std::max(width, std::min(34.0, f.a1 - a));
      if (f.a1 - (a + width) < 8.0) width = f.a1 - a;
      const double b = a + width;
      const double roll = rng.Uniform();
      if (!placed_landmark && width >= 14.0) {
        NamedBuilding(rng, f, a, b, max_depth);
        placed_landmark = true;
      } else if (roll < 0.80 || width > 26.0) {
        Building(rng, f, a, b, max_depth);
      } else if (roll < 0.87) {
        Gap(rng, f, a, b, max_depth, Material::kWall);
      } else if (roll < 0.94) {
        Gap(rng, f, a, b, max_depth, Material::kFence);
      } else {
        Gap(rng, f, a, b, max_depth, Material::kGrass);
      }
      a = b;
    }
  }

  // Box with extent [a, b] along the frontage, from `front + outward * -setback` going `depth` inwards.
  static void FootprintBox(const Frontage& f, double a, double b, double setback, double depth,
                           Eigen::Vector3f* lo, Eigen::Vector3f* hi, float z0, float z1) {
    const double face = f.front - f.outward * setback;
    const double back = face - f.outward * depth;
    if (f.axis == 0) {
      *lo = {F(a), F(std::min(face, back)), z0};
      *hi = {F(b), F(std::max(face, back)), z1};
    } else {
      *lo = {F(std::min(face, back)), F(a), z0};
      *hi = {F(std::max(face, back)), F(b), z1};
    }
  }

  void Building(Rng& rng, const Frontage& f, double a, double b, double max_depth) {
    const std::uint32_t obj = b_.NewObject("building", SemanticClass::kBuilding);
    FacadeStyle style = RandomStyle(rng);
    const std::uint16_t style_id = AddStyle(style);
    const int floors = std::min(8, 2 + static_cast<int>(std::floor(rng.Uniform() * rng.Uniform() * 7.0)));
    const double height = floors * style.floor_height + rng.Uniform(0.3, 1.2);
    const double setback = rng.Bernoulli(0.7) ? 0.0 : rng.Uniform(0.5, 2.5);
    const double depth = std::min(max_depth - setback, rng.Uniform(10.0, 18.0));
    const float tone = F(rng.Uniform());
    const std::uint32_t variant = Bits(rng);
    Eigen::Vector3f lo, hi;
    FootprintBox(f, a, b, setback, depth, &lo, &hi, kSidewalkHeight, F(height));
    b_.Box(obj, Material::kFacade, SemanticClass::kBuilding, lo, hi, tone, variant).style = style_id;
    if (floors >= 4 && rng.Bernoulli(0.3)) {
      // A set-back top storey.
      const double inset = rng.Uniform(1.5, 3.0);
      FootprintBox(f, a + inset, b - inset, setback + inset, depth - 2 * inset, &lo, &hi, F(height),
                   F(height + style.floor_height));
      if (b - a > 2 * inset + 3 && depth > 2 * inset + 3) {
        b_.Box(obj, Material::kFacade, SemanticClass::kBuilding, lo, hi, tone, variant ^ 0x5a5a5a5au).style =
            style_id;
      }
    }
    if (setback > 1.2 && rng.Bernoulli(0.5)) Hedge(rng, f, a + 0.5, b - 0.5, setback);
  }

  void NamedBuilding(Rng& rng, const Frontage& f, double a, double b, double max_depth) {
    if (next_building_name_ >= building_names_.size()) {
      Building(rng, f, a, b, max_depth);
      return;
    }
    const PlaceName pn = building_names_[next_building_name_++];
    const std::string category = pn.category;
    const std::uint32_t obj = b_.NewObject("building", SemanticClass::kBuilding, pn.name);
    FacadeStyle style = RandomStyle(rng);
    style.brick = category == "church" || category == "station" || category == "fire_station";
    style.wall_grey = F(style.brick ? rng.Uniform(110, 150) : rng.Uniform(185, 225));
    style.frame_grey = F(style.wall_grey > 175 ? rng.Uniform(50, 90) : 225);
    style.shop_front = false;
    style.window_height = std::min(style.floor_height - 1.0f, style.window_height + 0.4f);
    style.sill_height = std::max(0.5f, style.floor_height - style.window_height - 0.5f);
    const std::uint16_t style_id = AddStyle(style);
    const double depth = std::max(8.0, max_depth - 0.5);
    const float tone = F(rng.Uniform());
    const std::uint32_t variant = Bits(rng);
    Eigen::Vector3f lo, hi;
    double height = rng.Uniform(13.0, 17.0);
    if (category == "hospital" || category == "hotel" || category == "office")
      height = rng.Uniform(20.0, 26.0);
    if (category == "church") height = rng.Uniform(14.0, 17.0);
    const double setback = category == "townhall" || category == "museum" ? 2.0 : 0.0;
    FootprintBox(f, a, b, setback, depth, &lo, &hi, kSidewalkHeight, F(height));
    b_.Box(obj, Material::kFacade, SemanticClass::kBuilding, lo, hi, tone, variant).style = style_id;
    const Eigen::Vector3f footprint_centre = 0.5f * (lo + hi);
    if (category == "church" || category == "townhall" || category == "tower" || category == "station") {
      // A tower at the middle of the front.
      const double side = category == "church" ? 6.5 : 5.5;
      const double top =
          category == "church" ? height + rng.Uniform(20.0, 28.0) : height + rng.Uniform(9.0, 15.0);
      const double mid = 0.5 * (a + b);
      FootprintBox(f, mid - side / 2, mid + side / 2, setback - 0.8, side, &lo, &hi, kSidewalkHeight, F(top));
      b_.Box(obj, Material::kFacade, SemanticClass::kBuilding, lo, hi, tone, variant ^ 0x1234567u).style =
          style_id;
      FootprintBox(f, mid - side / 2 + 0.6, mid + side / 2 - 0.6, setback - 0.2, side - 1.2, &lo, &hi, F(top),
                   F(top + (category == "church" ? 5.0 : 2.0)));
      b_.Box(obj, Material::kRoof, SemanticClass::kBuilding, lo, hi, tone, variant);
    }
    city_.places.push_back(
        {pn.name, category, Eigen::Vector3d(footprint_centre.x(), footprint_centre.y(), 0.0), obj});
  }

  void Hedge(Rng& rng, const Frontage& f, double a, double b, double setback) {
    const std::uint32_t obj = b_.NewObject("hedge", SemanticClass::kVegetation);
    Eigen::Vector3f lo, hi;
    FootprintBox(f, a, b, 0.2, std::min(0.9, setback - 0.3), &lo, &hi, kSidewalkHeight,
                 F(rng.Uniform(0.9, 1.5)));
    const Look look = DrawLook(rng);
    b_.Box(obj, Material::kFoliage, SemanticClass::kVegetation, lo, hi, look.tone, look.variant);
  }

  void Gap(Rng& rng, const Frontage& f, double a, double b, double max_depth, Material kind) {
    // Lawn behind the front line.
    const std::uint32_t lawn = b_.NewObject("terrain", SemanticClass::kTerrain);
    Eigen::Vector3f lo, hi;
    FootprintBox(f, a, b, 0.3, max_depth - 0.3, &lo, &hi, kSidewalkHeight, kGrassTop);
    const Look lawn_look = DrawLook(rng);
    b_.Box(lawn, Material::kGrass, SemanticClass::kTerrain, lo, hi, lawn_look.tone, lawn_look.variant);
    if (kind == Material::kWall) {
      const std::uint32_t obj = b_.NewObject("wall", SemanticClass::kWall);
      FootprintBox(f, a, b, 0.0, 0.3, &lo, &hi, kSidewalkHeight, F(rng.Uniform(1.3, 2.4)));
      const Look wall_look = DrawLook(rng);
      b_.Box(obj, Material::kWall, SemanticClass::kWall, lo, hi, wall_look.tone, wall_look.variant);
    } else if (kind == Material::kFence) {
      const std::uint32_t obj = b_.NewObject("fence", SemanticClass::kFence);
      FootprintBox(f, a, b, 0.0, 0.06, &lo, &hi, kSidewalkHeight, F(rng.Uniform(1.1, 1.9)));
      const Look fence_look = DrawLook(rng);
      b_.Box(obj, Material::kFence, SemanticClass::kFence, lo, hi, fence_look.tone, fence_look.variant);
    }
    // Trees and bushes in the garden.
    const int trees = rng.UniformInt(1, std::max(1, static_cast<int>((b - a) / 7.0)));
    for (int t = 0; t < trees; ++t) {
      const double along = rng.Uniform(a + 2.0, b - 2.0);
      const double in = rng.Uniform(3.0, std::max(3.5, max_depth - 3.0));
      const double face = f.front - f.outward * in;
      const double x = f.axis == 0 ? along : face;
      const double y = f.axis == 0 ? face : along;
      if (rng.Bernoulli(0.6)) {
        AddTree(b_, rng, x, y, kSidewalkHeight);
      } else {
        AddBush(b_, rng, x, y);
      }
    }
  }

  // Park (lawn, trees, bushes, hedge) or square (paved, trees in rows, lamps).
  void OpenPlace(Rng& rng, double x0, double y0, double x1, double y1) {
    const PlaceName pn = kOpenPlaceNames[next_open_name_++ % kOpenPlaceNames.size()];
    const bool park = std::string(pn.category) == "park";
    const double sw = city_.grid.sidewalk_width;
    const std::uint32_t obj = b_.NewObject(
        park ? "park" : "square", park ? SemanticClass::kTerrain : SemanticClass::kSidewalk, pn.name);
    if (park) {
      const Look lawn_look = DrawLook(rng);
      b_.Box(obj, Material::kGrass, SemanticClass::kTerrain, {F(x0 + sw), F(y0 + sw), kSidewalkHeight},
             {F(x1 - sw), F(y1 - sw), kGrassTop}, lawn_look.tone, lawn_look.variant);
      // Hedges along the edges, with entrances in the middle of each side.
      const std::uint32_t hedge = b_.NewObject("hedge", SemanticClass::kVegetation);
      const float h = F(rng.Uniform(1.0, 1.4));
      const double mx = 0.5 * (x0 + x1), my = 0.5 * (y0 + y1);
      auto add = [&](double ax, double ay, double bx, double by) {
        const Look hedge_look = DrawLook(rng);
        b_.Box(hedge, Material::kFoliage, SemanticClass::kVegetation, {F(ax), F(ay), kGrassTop},
               {F(bx), F(by), h}, hedge_look.tone, hedge_look.variant);
      };
      add(x0 + sw, y0 + sw, mx - 3, y0 + sw + 0.8);
      add(mx + 3, y0 + sw, x1 - sw, y0 + sw + 0.8);
      add(x0 + sw, y1 - sw - 0.8, mx - 3, y1 - sw);
      add(mx + 3, y1 - sw - 0.8, x1 - sw, y1 - sw);
      add(x0 + sw, y0 + sw, x0 + sw + 0.8, my - 3);
      add(x0 + sw, my + 3, x0 + sw + 0.8, y1 - sw);
      add(x1 - sw - 0.8, y0 + sw, x1 - sw, my - 3);
      add(x1 - sw - 0.8, my + 3, x1 - sw, y1 - sw);
      const int trees = static_cast<int>((x1 - x0) * (y1 - y0) / 260.0);
      for (int t = 0; t < trees; ++t) {
        const double x = rng.Uniform(x0 + sw + 4, x1 - sw - 4), y = rng.Uniform(y0 + sw + 4, y1 - sw - 4);
        if (rng.Bernoulli(0.7)) {
          AddTree(b_, rng, x, y, kGrassTop, rng.Uniform(1.0, 1.5));
        } else {
          AddBush(b_, rng, x, y);
        }
      }
    } else {
      for (double x = x0 + sw + 6; x < x1 - sw - 4; x += 12) {
        for (double y = y0 + sw + 6; y < y1 - sw - 4; y += 12) {
          if (!rng.Bernoulli(0.65)) continue;
          const double dy = rng.Uniform(-1, 1);
          const double dx = rng.Uniform(-1, 1);
          AddTree(b_, rng, x + dx, y + dy, kSidewalkHeight);
        }
      }
      const std::uint32_t basin = b_.NewObject("fountain", SemanticClass::kWall);
      const double mx = 0.5 * (x0 + x1), my = 0.5 * (y0 + y1);
      const Look look = DrawLook(rng);
      b_.Cylinder(basin, Material::kWall, SemanticClass::kWall, F(mx), F(my), 4.0f, kSidewalkHeight, 0.75f,
                  look.tone, look.variant);
    }
    const Eigen::Vector3d centre(0.5 * (x0 + x1), 0.5 * (y0 + y1), 0.0);
    city_.places.push_back({pn.name, pn.category, centre, obj});
  }

  // Lamp posts, street trees, signs and traffic lights along every street segment.
  void MakeStreetFurniture() {
    const StreetGrid& g = city_.grid;
    const double rw = g.road_half_width;
    for (const StreetGrid::Segment& seg : g.segments) {
      Rng rng = Rng::Stream(options_.seed, Hash3(4, static_cast<std::uint64_t>(seg.id), 0));
      const Eigen::Vector2d pa = g.Position(seg.a), pb = g.Position(seg.b);
      const int axis = std::abs(pb.x() - pa.x()) > 1e-6 ? 0 : 1;  // direction the street runs
      const double s0 = (axis == 0 ? pa.x() : pa.y()) + rw + 1.0;
      const double s1 = (axis == 0 ? pb.x() : pb.y()) - rw - 1.0;
      const double c = axis == 0 ? pa.y() : pa.x();
      const bool trees = rng.Bernoulli(options_.tree_density);
      for (int side = -1; side <= 1; side += 2) {
        const double curb = c + side * rw;
        auto at = [&](double s, double off) {  // off: metres from the curb into the sidewalk
          const double across = curb + side * off;
          return axis == 0 ? Eigen::Vector2d(s, across) : Eigen::Vector2d(across, s);
        };
        // Lamp posts.
        std::vector<double> lamps;
        for (double s = s0 + rng.Uniform(3, 20); s < s1 - 2; s += rng.Uniform(24, 32)) {
          lamps.push_back(s);
          const Eigen::Vector2d p = at(s, 0.6);
          const std::uint32_t obj = b_.NewObject("pole", SemanticClass::kPole);
          const float h = F(rng.Uniform(6.0, 8.0));
          const float tone = F(rng.Uniform());
          b_.Cylinder(obj, Material::kPole, SemanticClass::kPole, F(p.x()), F(p.y()), 0.09f, kSidewalkHeight,
                      h, tone, Bits(rng));
          // The head reaches over the road.
          const Eigen::Vector2d q = at(s, -1.2);
          Eigen::Vector3f lo(F(std::min(p.x(), q.x()) - 0.12), F(std::min(p.y(), q.y()) - 0.12), h - 0.2f);
          Eigen::Vector3f hi(F(std::max(p.x(), q.x()) + 0.12), F(std::max(p.y(), q.y()) + 0.12), h);
          b_.Box(obj, Material::kLamp, SemanticClass::kPole, lo, hi, tone, Bits(rng));
        }
        // Street trees between the lamps.
        if (trees) {
          for (double s = s0 + rng.Uniform(2, 8); s < s1 - 2; s += rng.Uniform(9, 15)) {
            bool clear = true;
            for (double l : lamps) clear = clear && std::abs(l - s) > 3.0;
            if (!clear) continue;
            const Eigen::Vector2d p = at(s, 1.3);
            AddTree(b_, rng, p.x(), p.y(), kSidewalkHeight);
          }
        }
        // Signs and traffic lights for the traffic arriving at this segment's ends on this side: traffic on
        // the right of its direction; on side -1 of an x-street, it drives +x (towards b).
        for (int end = 0; end < 2; ++end) {
          // Which end this side's traffic approaches: driving +axis keeps the street on its left, so its
          // right side is -1 for axis 0 (y smaller) and +1 for axis 1 (x larger).
          const int dir = (axis == 0 ? -side : side);  // +1: travels towards b
          const bool approaching_b = dir > 0;
          if ((end == 1) != approaching_b) continue;
          const double s_end = approaching_b ? s1 : s0;
          const int facing = axis == 0 ? (approaching_b ? 2 : 0) : (approaching_b ? 3 : 1);
          const int inter = approaching_b ? seg.b : seg.a;
          Rng irng = Rng::Stream(options_.seed, Hash3(5, static_cast<std::uint64_t>(inter), 0));
          const bool lights = irng.Bernoulli(0.4);
          if (lights) {
            const Eigen::Vector2d p = at(s_end - dir * 0.5, 0.5);
            AddTrafficLight(b_, rng, p, facing);
          } else if (rng.Bernoulli(0.6)) {
            const Eigen::Vector2d p = at(s_end - dir * rng.Uniform(4.0, 12.0), 0.5);
            AddTrafficSign(b_, rng, p, facing);
          }
        }
      }
    }
  }

  // Parked cars, persons and bicycles: drawn from the traffic seed, so that a second drive through the same
  // town can meet other ones.
  void MakeTraffic() {
    const StreetGrid& g = city_.grid;
    const std::uint64_t traffic_seed = options_.traffic_seed != 0 ? options_.traffic_seed : options_.seed;
    const double rw = g.road_half_width;
    for (const StreetGrid::Segment& seg : g.segments) {
      Rng rng = Rng::Stream(traffic_seed, Hash3(6, static_cast<std::uint64_t>(seg.id), 0x7aff1c));
      const Eigen::Vector2d pa = g.Position(seg.a), pb = g.Position(seg.b);
      const int axis = std::abs(pb.x() - pa.x()) > 1e-6 ? 0 : 1;
      const double s0 = (axis == 0 ? pa.x() : pa.y()) + rw + 14.0;
      const double s1 = (axis == 0 ? pb.x() : pb.y()) - rw - 14.0;
      const double c = axis == 0 ? pa.y() : pa.x();
      const double density = options_.parked_car_density * rng.Uniform(0.3, 1.7);
      for (int side = -1; side <= 1; side += 2) {
        const double lane = c + side * 0.5 * (g.parking_inner + rw);
        for (double s = s0 + rng.Uniform(0, 4); s < s1 - 4.0;) {
          const double length = rng.Uniform(3.9, 4.8);
          if (rng.Uniform() < density) {
            AddCar(b_, rng, axis, s + length / 2, lane, length);
            s += length + rng.Uniform(0.8, 2.5);
          } else {
            s += rng.Uniform(3.0, 7.0);
          }
        }
        // Persons on the sidewalk, bicycles by the curb.
        const double s_lo = s0 - 10.0, s_hi = s1 + 10.0;
        const int persons =
            static_cast<int>(std::floor((s_hi - s_lo) * options_.person_density * 2.0 * rng.Uniform()));
        for (int k = 0; k < persons; ++k) {
          const double s = rng.Uniform(s_lo, s_hi);
          const double across = c + side * (rw + rng.Uniform(1.8, 3.2));
          AddPerson(b_, rng, axis == 0 ? s : across, axis == 0 ? across : s);
        }
        const int bikes =
            static_cast<int>(std::floor((s_hi - s_lo) * options_.bicycle_density * 2.0 * rng.Uniform()));
        for (int k = 0; k < bikes; ++k) {
          const double s = rng.Uniform(s_lo, s_hi);
          const double across = c + side * (rw + 0.35);
          AddBicycle(b_, rng, axis, axis == 0 ? s : across, axis == 0 ? across : s);
        }
      }
    }
  }

  std::uint16_t AddStyle(const FacadeStyle& s) {
    city_.styles.push_back(s);
    return static_cast<std::uint16_t>(city_.styles.size() - 1);
  }

  void Finish() {
    Eigen::Vector2f lo(1e9f, 1e9f), hi(-1e9f, -1e9f);
    float top = 0;
    for (const Primitive& p : city_.primitives) {
      lo = lo.cwiseMin(p.lo.head<2>());
      hi = hi.cwiseMax(p.hi.head<2>());
      top = std::max(top, p.hi.z());
    }
    city_.min_corner = lo.cast<double>();
    city_.max_corner = hi.cast<double>();
    city_.max_height = top;
  }

  CityOptions options_;
  City city_;
  Builder b_;
  std::vector<PlaceName> building_names_;
  size_t next_building_name_ = 0;
  size_t next_open_name_ = 0;
};

}  // namespace

int StreetGrid::SegmentBetween(int a, int b) const {
  const int lo = std::min(a, b), hi = std::max(a, b);
  for (const Segment& s : segments) {
    if (s.a == lo && s.b == hi) return s.id;
  }
  return -1;
}

void CityOptions::Check() const {
  Require(blocks_x >= 3 && blocks_x <= 60, "CityOptions.blocks_x must be in [3, 60]");
  Require(blocks_y >= 3 && blocks_y <= 60, "CityOptions.blocks_y must be in [3, 60]");
  Require(std::isfinite(min_block) && min_block >= 50.0, "CityOptions.min_block must be at least 50 m");
  Require(std::isfinite(max_block) && max_block >= min_block && max_block <= 400.0,
          "CityOptions.max_block must be in [min_block, 400] m");
  auto fraction = [](double v) { return std::isfinite(v) && v >= 0.0 && v <= 1.0; };
  Require(fraction(parked_car_density), "CityOptions.parked_car_density must be in [0, 1]");
  Require(fraction(tree_density), "CityOptions.tree_density must be in [0, 1]");
  Require(std::isfinite(person_density) && person_density >= 0 && person_density <= 0.2,
          "CityOptions.person_density must be in [0, 0.2] per metre");
  Require(std::isfinite(bicycle_density) && bicycle_density >= 0 && bicycle_density <= 0.2,
          "CityOptions.bicycle_density must be in [0, 0.2] per metre");
  Require(park_blocks >= 0 && park_blocks <= 6, "CityOptions.park_blocks must be in [0, 6]");
}

City GenerateCity(const CityOptions& options) {
  options.Check();
  return CityGenerator(options).Run();
}

}  // namespace semslam::sim
