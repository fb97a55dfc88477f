// World files (libs/world: `concert up --world`, `concert sim world`, the simulator) and the
// ground truth the simulator and the tasks compute from a world: mark poses and ArUco cells,
// sanding surface heights, moving obstacles along their paths. Documented failure: WorldError.
#include <cmath>

#include "concert/world/aruco.hpp"
#include "concert/world/geometry.hpp"
#include "concert/world/world.hpp"
#include "fuzz.hpp"

namespace {

using namespace concert;

void use(const world::World& w) {
  double sum = 0.0;
  for (const world::MarkTruth& m : world::mark_truth(w)) {
    sum += m.centre.sum() + m.normal.sum();
    if (m.type == world::Mark::Type::kAruco) {
      const world::ArucoCells cells = world::aruco_cells(m.dictionary, m.id);
      CONCERT_FUZZ_CHECK(cells.white.size() == static_cast<size_t>(cells.side * cells.side),
                         "ArUco cells do not fill the marker");
    }
  }
  for (const world::Surface& s : w.surfaces) {
    for (int i = 0; i <= 4; ++i) {
      const double u = s.at.x() + s.size.x() * (i / 4.0 - 0.5);
      const double z = s.at.y() + s.size.y() * (i / 4.0 - 0.5);
      sum += world::surface_height(s, u, z) + world::surface_point(w, s, u, z).sum();
    }
  }
  for (const world::WorldShape& o : w.obstacles) {
    sum += world::path_length(o);
    // The simulator asks at every step, for as long as it runs (a day of simulated time here).
    for (const double t : {0.0, 0.001, 1.0, 7.5, 60.0, 3600.0, 86400.0}) {
      sum += world::obstacle_position(o, t).sum();
    }
  }
  volatile double sink = sum;
  (void)sink;
}

}  // namespace

extern "C" int LLVMFuzzerTestOneInput(const uint8_t* data, size_t size) {
  world::World w;
  try {
    w = world::parse_world_yaml(std::string(fuzz::text_of(data, size)), "world.yaml");
  } catch (const world::WorldError&) {
    return 0;
  }
  use(w);
  return 0;
}

void concert::fuzz::write_seeds(SeedWriter& seeds) {
  seeds.add_files(source_dir() / "deploy/demo", "_site.yaml");
  seeds.add_files(source_dir() / "libs/world/test/fixtures", ".yaml");
  seeds.add_tokens(kYamlTokens);
  seeds.add_tokens(world::aruco_dictionary_names());
  seeds.add_tokens(
      {"loop", "pingpong", "once", "box", "cylinder", "+x", "-x", "+y", "-y", "blob", "aruco"});
}
