#pragma once
// Drilling sites drawn from a seed (issue #51): what a crew might mark on a site the project never
// rehearsed. Each site is one wall in front of the robot's start (the robot at the origin facing
// +x), not square to it, one drilling area on it, and boxes standing against the wall beside the
// area (a pallet, a stack of blocks) that limit where the base may stand:
//   * the wall's face 1.6-2.8 m from the start, its normal turned by up to +-0.25 rad;
//   * the area: a pair of blue blobs 0.1 m apart at any angle (the paper's scenario 1 clusters),
//     or an ArUco marker of any id of the pattern table, its holes laid out by its pattern; the
//     mark and every hole between 0.4 and 2.6 m high, the mark within +-0.8 m of the face's
//     centre along the wall;
//   * 0-2 boxes against the face, 0.5-1.0 m beside the area's outermost hole or mark;
//   * the morphology as the paper assigns it by height: A, and C (the Passive Base Link, base at
//     about 0.75 m) for an area whose highest hole is above 2.4 m.
// Plain C++ and the world library: no DDS, no simulator (drill_sites_test checks the drawing).
#include <algorithm>
#include <cmath>
#include <cstdint>
#include <iomanip>
#include <random>
#include <sstream>
#include <string>
#include <vector>

#include "concert/world/geometry.hpp"
#include "concert/world/world.hpp"
#include "drill/patterns.hpp"

namespace concert::system_test {

struct GeneratedSite {
  std::string name;          ///< "site_07": the area's name too
  std::string world_yaml;    ///< the world file's text
  std::string mission_yaml;  ///< one area, the mark's centre as its point
  bool morphology_c{false};  ///< C (highest hole above 2.4 m), else A
  std::string description;   ///< one line for the bench's output
};

namespace drill_sites_detail {

inline double uniform(std::mt19937_64& rng, double lo, double hi) {
  return std::uniform_real_distribution<double>(lo, hi)(rng);
}

// Offsets [u, z] of the holes (and of the mark's own extent) from the mark's centre on the face:
// the marker's x is the face's u when the marker is upright (angle 0).
struct Layout {
  std::vector<Eigen::Vector2d> holes;
  Eigen::Vector2d low{0, 0}, high{0, 0};  // bounding box of the holes and the mark
};

inline Layout pattern_layout(const drill::HolePattern& p, double marker_size) {
  Layout l;
  const Eigen::Vector2d along(std::cos(p.direction), std::sin(p.direction));
  for (int i = 0; i < p.count; ++i)
    l.holes.push_back(p.centre + (i - (p.count - 1) / 2.0) * p.spacing * along);
  l.low = Eigen::Vector2d::Constant(-marker_size / 2);
  l.high = Eigen::Vector2d::Constant(marker_size / 2);
  for (const Eigen::Vector2d& h : l.holes) {
    l.low = l.low.cwiseMin(h);
    l.high = l.high.cwiseMax(h);
  }
  return l;
}

}  // namespace drill_sites_detail

inline constexpr double kSiteLowest = 0.4, kSiteHighest = 2.6, kSiteMorphologyC = 2.4;

/// Site `index` of `seed`: drawn from its own generator (seeded with both), so a site is the same
/// whatever the count asked for.
inline GeneratedSite generate_site(std::uint64_t seed, int index, const drill::PatternTable& patterns) {
  using drill_sites_detail::uniform;
  std::seed_seq seq{static_cast<std::uint32_t>(seed), static_cast<std::uint32_t>(seed >> 32),
                    static_cast<std::uint32_t>(index)};
  std::mt19937_64 rng(seq);
  GeneratedSite site;
  char name[32];
  std::snprintf(name, sizeof name, "site_%02d", index);
  site.name = name;

  // The wall: a 6 m x 3.2 m box 0.2 m thick, its -x face towards the start.
  const double distance = uniform(rng, 1.6, 2.8);
  const double yaw = uniform(rng, -0.25, 0.25);
  const Eigen::Vector2d into(std::cos(yaw), std::sin(yaw));  // from the start into the wall
  world::WorldShape wall;
  wall.name = "site_wall";
  wall.size = {0.2, 6.0, 3.2};
  wall.position = Eigen::Vector3d((distance + 0.1) * into.x(), (distance + 0.1) * into.y(), 1.6);
  wall.yaw = yaw;

  // The area's marks and its holes' layout on the face.
  const bool blobs = uniform(rng, 0.0, 1.0) < 0.5;
  drill_sites_detail::Layout layout;
  int marker_id = 0;
  double pair_angle = 0.0;
  if (blobs) {
    pair_angle = uniform(rng, 0.0, M_PI);
    const Eigen::Vector2d half = 0.05 * Eigen::Vector2d(std::cos(pair_angle), std::sin(pair_angle));
    layout.holes = {-half, half};
    layout.low = (-half).cwiseMin(half) - Eigen::Vector2d::Constant(0.0125);
    layout.high = (-half).cwiseMax(half) + Eigen::Vector2d::Constant(0.0125);
  } else {
    const auto& all = patterns.patterns();
    const auto pick = std::uniform_int_distribution<std::size_t>(0, all.size() - 1)(rng);
    marker_id = all[pick].id;
    layout = drill_sites_detail::pattern_layout(all[pick], patterns.marker_size());
  }
  const double u = uniform(rng, -0.8, 0.8);
  const double z = uniform(rng, kSiteLowest - layout.low.y(), kSiteHighest - layout.high.y());
  double highest = 0.0;
  for (const Eigen::Vector2d& h : layout.holes) highest = std::max(highest, z + h.y());
  site.morphology_c = highest > kSiteMorphologyC;

  std::ostringstream w;
  w << std::setprecision(9) << "# " << site.name << " of seed " << seed
    << " (tests/system/drill_sites.hpp)\nfloor:\n  friction: 1.0\nwalls:\n  - name: " << wall.name
    << "\n    size: [0.2, 6.0, 3.2]\n    position: [" << wall.position.x() << ", " << wall.position.y()
    << ", 1.6]\n    yaw: " << yaw << "\n";

  // Boxes against the face beside the area, each side by chance.
  std::ostringstream boxes;
  boxes << std::setprecision(9);
  int box_count = 0;
  for (const double side : {-1.0, 1.0}) {
    if (uniform(rng, 0.0, 1.0) < 0.5) continue;
    const double gap = uniform(rng, 0.5, 1.0);
    const double width = uniform(rng, 0.3, 0.8), depth = uniform(rng, 0.3, 0.8), height = uniform(rng, 0.6, 2.0);
    const double edge = u + (side < 0 ? layout.low.x() : layout.high.x());
    const double centre_u = edge + side * (gap + width / 2);
    const Eigen::Vector3d at =
        world::face_point(wall, world::Face::kMinusX, {centre_u, height / 2}, depth / 2);
    boxes << "  - {name: box_" << (side < 0 ? "left" : "right") << ", size: [" << depth << ", " << width << ", "
          << height << "], position: [" << at.x() << ", " << at.y() << ", " << at.z() << "], yaw: " << yaw
          << "}\n";
    ++box_count;
  }
  if (box_count > 0) w << "obstacles:\n" << boxes.str();

  w << "marks:\n";
  if (blobs) {
    for (std::size_t i = 0; i < layout.holes.size(); ++i) {
      w << "  - {type: blob, name: " << site.name << "_blob_" << i + 1 << ", wall: " << wall.name
        << ", face: -x, at: [" << u + layout.holes[i].x() << ", " << z + layout.holes[i].y()
        << "], diameter: 0.025}\n";
    }
  } else {
    w << "  - {type: aruco, name: " << site.name << "_marker, wall: " << wall.name << ", face: -x, at: [" << u
      << ", " << z << "], size: " << patterns.marker_size() << ", dictionary: " << patterns.dictionary()
      << ", id: " << marker_id << ", angle: 0.0}\n";
  }
  site.world_yaml = w.str();

  // The area's point: the mark's centre on the face (a crew's click on it).
  const Eigen::Vector3d point = world::face_point(wall, world::Face::kMinusX, {u, z});
  std::ostringstream m;
  m << std::setprecision(9) << "name: generated " << site.name << "\ndepth: 0.03\nareas:\n  - {name: " << site.name
    << ", marks: " << (blobs ? "blobs" : "aruco") << ", point: [" << point.x() << ", " << point.y() << ", "
    << point.z() << "]" << (blobs ? ", expected: 2" : "") << "}\n";
  site.mission_yaml = m.str();

  std::ostringstream d;
  d << std::fixed << std::setprecision(2) << "wall " << distance << " m away, yaw " << std::showpos << yaw
    << std::noshowpos << " rad; ";
  if (blobs) {
    d << "2 blobs at " << std::setprecision(0) << pair_angle * 180 / M_PI << std::setprecision(2) << " deg";
  } else {
    d << "ArUco id " << marker_id << " (" << layout.holes.size() << (layout.holes.size() == 1 ? " hole)" : " holes)");
  }
  d << " at u " << std::showpos << u << std::noshowpos << " m, z " << z << " m, holes up to " << highest << " m; "
    << box_count << (box_count == 1 ? " box" : " boxes") << " beside; morphology " << (site.morphology_c ? "C" : "A");
  site.description = d.str();
  return site;
}

/// Sites 1..count of `seed`.
inline std::vector<GeneratedSite> generate_sites(std::uint64_t seed, int count, const drill::PatternTable& patterns) {
  std::vector<GeneratedSite> out;
  for (int k = 1; k <= count; ++k) out.push_back(generate_site(seed, k, patterns));
  return out;
}

}  // namespace concert::system_test
