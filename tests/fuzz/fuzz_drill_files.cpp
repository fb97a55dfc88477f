// The drilling service's files (services/drill): mission files (`concert drill run --mission`,
// the GUI's mission builder) and ArUco hole-pattern tables. The input goes to both parsers.
// What parses must hold what the file formats promise: a mission has areas with unique names,
// each found one way, finite numbers and a depth in (0, 0.3] m; a pattern table has a positive
// marker size and rows that fit the promise of count and spacing. Documented failure:
// DrillError (and config::ConfigError for a pattern table's YAML).
//
// Seeds: the shipped pattern table, the demo mission, the tests' mission fixtures.
#include <cmath>
#include <set>
#include <string>

#include "concert/config/config.hpp"
#include "drill/mission.hpp"
#include "drill/patterns.hpp"
#include "fuzz.hpp"

namespace {

using namespace concert;

void check(const drill::Mission& m) {
  CONCERT_FUZZ_CHECK(!m.areas.empty(), "a mission without areas");
  CONCERT_FUZZ_CHECK(m.depth > 0.0 && m.depth <= 0.3, "a depth outside (0, 0.3] m");
  std::set<std::string> names;
  for (const drill::AreaSpec& a : m.areas) {
    CONCERT_FUZZ_CHECK(names.insert(a.name).second, "two areas named '" + a.name + "'");
    const int ways = (a.wall.empty() ? 0 : 1) + (a.point ? 1 : 0) + (a.pixel ? 1 : 0);
    CONCERT_FUZZ_CHECK(ways == 1, "an area found in " + std::to_string(ways) + " ways");
    CONCERT_FUZZ_CHECK(a.at.allFinite(), "a wall position that is not finite");
    if (a.point) CONCERT_FUZZ_CHECK(a.point->allFinite(), "a point that is not finite");
    if (a.pixel) CONCERT_FUZZ_CHECK(a.pixel->allFinite(), "a pixel that is not finite");
    CONCERT_FUZZ_CHECK(a.expected >= 0, "a negative count of expected holes");
    if (!a.wall.empty()) CONCERT_FUZZ_CHECK(!m.ifc.empty(), "a wall area without an IFC file");
  }
}

void check(const drill::PatternTable& t) {
  CONCERT_FUZZ_CHECK(t.marker_size() > 0.0 && std::isfinite(t.marker_size()),
                     "a marker size that is not positive");
  std::set<int> ids;
  for (const drill::HolePattern& p : t.patterns()) {
    CONCERT_FUZZ_CHECK(ids.insert(p.id).second, "two patterns of one marker id");
    CONCERT_FUZZ_CHECK(t.find(p.id) != nullptr, "a pattern its table cannot find");
    CONCERT_FUZZ_CHECK(p.count >= 1, "a row of no holes");
    CONCERT_FUZZ_CHECK(p.count == 1 || (p.spacing > 0.0 && std::isfinite(p.spacing)),
                       "a row whose spacing is not positive");
    CONCERT_FUZZ_CHECK(p.centre.allFinite() && std::isfinite(p.direction),
                       "a row centre or direction that is not finite");
  }
}

}  // namespace

extern "C" int LLVMFuzzerTestOneInput(const uint8_t* data, size_t size) {
  const std::string text(fuzz::text_of(data, size));
  try {
    check(drill::parse_mission(text, "mission.yaml", "/nonexistent-base"));
  } catch (const drill::DrillError&) {
  }
  try {
    check(drill::parse_patterns(text, "patterns.yaml"));
  } catch (const drill::DrillError&) {
  } catch (const config::ConfigError&) {
  }
  return 0;
}

void concert::fuzz::write_seeds(SeedWriter& seeds) {
  seeds.add_files(source_dir() / "services/drill/config", ".yaml");
  seeds.add_files(source_dir() / "deploy/demo", "_mission.yaml");
  seeds.add_tokens(kYamlTokens);
  seeds.add_tokens({"name", "ifc", "storey", "patterns", "depth", "areas", "marks", "blobs",
                    "aruco", "wall", "at", "face", "left", "right", "auto", "point", "pixel",
                    "expected", "dictionary", "marker_size", "id", "centre", "direction",
                    "count", "spacing", "DICT_4X4_50", "DICT_6X6_250"});
}
