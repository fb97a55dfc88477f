// Scan files (libs/topology scan_io: YAML in every form, JSON) and what `concert discover` does
// with the scan: the module tree rebuilt with the real catalogues (both frame orders), rendered
// as JSON and text. Documented failures: ScanFormatError. Properties: a scan read back from
// scan_to_yaml / scan_to_json is the same scan; Discovery::rebuild never throws.
#include "bus.hpp"
#include "concert/topology/reconstruction.hpp"
#include "concert/topology/scan_io.hpp"
#include "fuzz.hpp"

namespace {

using namespace concert;
using topology::EscScan;

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
  for (const topology::EscCatalog& catalog : fuzz::catalogues()) {
    for (const auto order : {topology::PortOrder::kReal0312, topology::PortOrder::kNumeric0123}) {
      const topology::Discovery discovery(catalog, topology::DiscoveryParams{order});
      const topology::ModuleTree tree = discovery.rebuild(scan);
      volatile size_t sink = topology::tree_to_json(tree).dump().size();
      sink = sink + topology::tree_to_text(tree).size();
      (void)sink;
    }
  }
}

/// `text` through one of the scan readers, and what the stack does with the scan.
void parse(EscScan (*read)(std::string_view, const std::string&), std::string_view text,
           const std::string& source) {
  EscScan scan;
  try {
    scan = read(text, source);
  } catch (const topology::ScanFormatError&) {
    return;
  }
  check_round_trip(scan);
  discover(scan);
}

}  // namespace

extern "C" int LLVMFuzzerTestOneInput(const uint8_t* data, size_t size) {
  const std::string_view text = fuzz::text_of(data, size);
  // Every input as both formats: the file name's extension is all that chooses between them.
  parse(topology::parse_scan_yaml, text, "scan.yaml");
  parse(topology::parse_scan_json, text, "scan.json");
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
