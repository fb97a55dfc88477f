// Scan files (libs/topology scan_io: YAML in every form, JSON) and what `concert discover` does
// with the scan: the module tree rebuilt with the real catalogues (both frame orders), rendered
// as JSON and text. Documented failures: ScanFormatError. Properties: a scan read back from
// scan_to_yaml / scan_to_json is the same scan; Discovery::rebuild never throws.
#include <optional>
#include <vector>

#include "concert/topology/esc_catalog.hpp"
#include "concert/topology/reconstruction.hpp"
#include "concert/topology/scan_io.hpp"
#include "fuzz.hpp"

namespace {

using namespace concert;
using topology::EscScan;

/// The catalogues the stack runs with: the project's module database and the public one (each
/// alone: merged, the public entries replace the project's, which share identities).
const std::vector<topology::EscCatalog>& catalogues() {
  static const std::vector<topology::EscCatalog> c{
      topology::EscCatalog::load(fuzz::source_dir() / "data/module_db"),
      topology::EscCatalog::load(fuzz::shared_data_dir() / "concert_resources")};
  return c;
}

void check_round_trip(const EscScan& scan) {
  const std::string yaml = topology::scan_to_yaml(scan);
  const std::string json = topology::scan_to_json(scan).dump();
  try {
    CONCERT_FUZZ_CHECK(topology::parse_scan_yaml(yaml, "<yaml>") == scan,
                       "scan_to_yaml does not read back as the same scan:\n" + yaml);
    CONCERT_FUZZ_CHECK(topology::parse_scan_json(json, "<json>") == scan,
                       "scan_to_json does not read back as the same scan:\n" + json);
  } catch (const topology::ScanFormatError& e) {
    CONCERT_FUZZ_CHECK(false, std::string("a written scan is refused: ") + e.what() + "\n" + yaml);
  }
}

void discover(const EscScan& scan) {
  for (const topology::EscCatalog& catalog : catalogues()) {
    for (const auto order : {topology::PortOrder::kReal0312, topology::PortOrder::kNumeric0123}) {
      const topology::Discovery discovery(catalog, topology::DiscoveryParams{order});
      const topology::ModuleTree tree = discovery.rebuild(scan);
      volatile size_t sink = topology::tree_to_json(tree).dump().size();
      sink = sink + topology::tree_to_text(tree).size();
      (void)sink;
    }
  }
}

void parse(std::optional<EscScan> (*read)(std::string_view), std::string_view text) {
  const std::optional<EscScan> scan = read(text);
  if (!scan) return;
  check_round_trip(*scan);
  discover(*scan);
}

}  // namespace

extern "C" int LLVMFuzzerTestOneInput(const uint8_t* data, size_t size) {
  const std::string_view text = fuzz::text_of(data, size);
  // Every input as both formats: the file name's extension is all that chooses between them.
  parse(
      [](std::string_view t) -> std::optional<EscScan> {
        try {
          return topology::parse_scan_yaml(t, "scan.yaml");
        } catch (const topology::ScanFormatError&) {
          return std::nullopt;
        }
      },
      text);
  parse(
      [](std::string_view t) -> std::optional<EscScan> {
        try {
          return topology::parse_scan_json(t, "scan.json");
        } catch (const topology::ScanFormatError&) {
          return std::nullopt;
        }
      },
      text);
  return 0;
}

void concert::fuzz::write_seeds(SeedWriter& seeds) {
  // The real scan of the CONCERT robot (the master's mapping form) and the repository's scans.
  seeds.add_files(shared_data_dir() / "ethercat", ".yaml");
  seeds.add_files(source_dir() / "services/discovery/examples", ".yaml");
  seeds.add_files(source_dir() / "services/discovery/examples", ".json");
  seeds.add_tokens(kYamlTokens);
  seeds.add_tokens(kJsonTokens);
}
