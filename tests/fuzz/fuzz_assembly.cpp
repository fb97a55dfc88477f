// Assembly files (libs/simbus: `concert up --assembly`, `concert sim swap`, `concert scan show`)
// and what the stack does with one: checked against the real catalogues, the simulated bus's
// scan (faults applied), the tree it describes, and discovery on that scan. Documented
// failures: AssemblyError. Properties: assembly_to_yaml reads back as the same assembly;
// without faults, discovery rebuilds exactly the tree the assembly describes (both frame orders).
#include <vector>

#include "bus.hpp"
#include "concert/simbus/assembly.hpp"
#include "concert/topology/scan_io.hpp"
#include "fuzz.hpp"

namespace {

using namespace concert;

/// True if `text` holds only what a YAML stream may: UTF-8 without control characters other
/// than tab, line feed and carriage return. yaml-cpp reads other bytes as they come, and its
/// emitter writes them differently (U+FFFD for bytes that are not UTF-8, NUL cut), so names
/// holding them cannot read back as written.
bool yaml_printable(std::string_view text) {
  if (!fuzz::valid_utf8(text)) return false;
  for (size_t i = 0; i < text.size(); ++i) {
    const auto c = static_cast<unsigned char>(text[i]);
    if ((c < 0x20 && c != '\t' && c != '\n' && c != '\r') || c == 0x7f) return false;
    if (c == 0xc2 && i + 1 < text.size()) {  // C1 controls U+0080..U+009F, but NEL (U+0085)
      const auto next = static_cast<unsigned char>(text[i + 1]);
      if (next >= 0x80 && next <= 0x9f && next != 0x85) return false;
    }
  }
  return true;
}

/// Names and keys read back as written (for text a YAML stream may hold).
void check_round_trip(const simbus::Assembly& assembly, std::string_view text) {
  if (!yaml_printable(text)) return;
  const std::string yaml = simbus::assembly_to_yaml(assembly);
  simbus::Assembly back;
  try {
    back = simbus::parse_assembly(yaml, "<assembly_to_yaml>");
  } catch (const simbus::AssemblyError& e) {
    CONCERT_FUZZ_CHECK(false, std::string("assembly_to_yaml wrote what parse_assembly refuses: ") +
                                  e.what() + "\n" + yaml);
  }
  CONCERT_FUZZ_CHECK(back.modules == assembly.modules && back.faults == assembly.faults,
                     "assembly_to_yaml does not read back as the same assembly:\n" + yaml);
}

void simulate(const simbus::Assembly& assembly, const topology::EscCatalog& catalog) {
  for (const auto order : {topology::PortOrder::kReal0312, topology::PortOrder::kNumeric0123}) {
    try {
      simbus::validate(assembly, catalog, order);
    } catch (const simbus::AssemblyError&) {
      return;
    }
    volatile size_t sink =
        topology::tree_to_json(fuzz::simulate_and_rebuild(assembly, catalog, order)).dump().size();
    (void)sink;
  }
}

}  // namespace

extern "C" int LLVMFuzzerTestOneInput(const uint8_t* data, size_t size) {
  simbus::Assembly assembly;
  try {
    assembly = simbus::parse_assembly(fuzz::text_of(data, size), "assembly.yaml");
  } catch (const simbus::AssemblyError&) {
    return 0;
  }
  check_round_trip(assembly, fuzz::text_of(data, size));
  for (const topology::EscCatalog& catalog : fuzz::catalogues()) simulate(assembly, catalog);
  return 0;
}

void concert::fuzz::write_seeds(SeedWriter& seeds) {
  seeds.add_files(source_dir() / "libs/simbus/examples", ".yaml");
  seeds.add_files(source_dir() / "deploy/demo", "_robot.yaml");
  seeds.add_tokens(kYamlTokens);
  seeds.add_tokens({"upside_down", "broken_link", "unknown_identity", "wrong_topology",
                    "upstream_port", "identity", "esc", "topology", "connector", "robot_id",
                    "parent", "faults", "modules"});
}
