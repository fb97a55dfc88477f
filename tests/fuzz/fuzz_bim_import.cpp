// The IFC import step's output (libs/bim: tools/ifc_import writes model.json and the binary mesh
// file it names; read_import reads them back, and the storey maps are sliced from what it read).
// The step is another program (Node.js + web-ifc) whose output the C++ side must not trust: it
// may be cut short, come from another version, or be edited. The input is the JSON, then a NUL,
// then the binary file's bytes. Documented failure: BimError.
//
// Seeds: the step's real output for the IfcOpenHouse IFC file of the shared data, and a small
// two-wall building.
#include <cstring>
#include <filesystem>
#include <fstream>
#include <sstream>
#include <string>
#include <vector>

#include "concert/bim/model.hpp"
#include "concert/bim/storey_map.hpp"
#include "fuzz.hpp"

namespace {

using namespace concert;

std::string file_bytes(const std::filesystem::path& file) {
  std::ifstream in(file, std::ios::binary);
  std::ostringstream s;
  s << in.rdbuf();
  return s.str();
}

/// A building of two 1 m long walls on one storey, in the step's format.
std::string two_walls() {
  std::vector<float> v;
  std::vector<uint32_t> idx;
  for (int wall = 0; wall < 2; ++wall) {
    const float x0 = wall == 0 ? 0.0f : 2.0f;
    for (const float z : {0.0f, 2.5f}) {
      for (const float y : {0.0f, 1.0f}) {
        v.insert(v.end(), {x0, y, z, x0 + 0.2f, y, z});
      }
    }
    for (const uint32_t i : {0u, 1u, 2u, 2u, 1u, 3u, 4u, 5u, 6u, 6u, 5u, 7u}) idx.push_back(i);
  }
  std::string json = R"({"format": "concert-ifc-import", "version": 1, "source": "walls.ifc",
 "schema": "IFC4", "length_unit_m": 1.0,
 "binary": {"file": "model.bin", "vertex_count": 16, "index_count": 24},
 "storeys": [{"name": "Ground", "global_id": "S1", "elevation": 0.0}],
 "elements": [
  {"global_id": "W1", "ifc_type": "IFCWALL", "category": "wall", "name": "a", "storey": "S1",
   "storey_from": "relation", "host": null, "placement": null,
   "vertex_offset": 0, "vertex_count": 8, "index_offset": 0, "index_count": 12},
  {"global_id": "W2", "ifc_type": "IFCWALL", "category": "wall", "name": "b", "storey": "S1",
   "storey_from": "height", "host": null,
   "placement": {"origin": [2, 0, 0], "x_axis": [0, 1, 0]},
   "vertex_offset": 8, "vertex_count": 8, "index_offset": 12, "index_count": 12}]})";
  std::string bin(v.size() * sizeof(float) + idx.size() * sizeof(uint32_t), '\0');
  std::memcpy(bin.data(), v.data(), v.size() * sizeof(float));
  std::memcpy(bin.data() + v.size() * sizeof(float), idx.data(), idx.size() * sizeof(uint32_t));
  return json + std::string(1, '\0') + bin;
}

}  // namespace

extern "C" int LLVMFuzzerTestOneInput(const uint8_t* data, size_t size) {
  const auto parts = fuzz::split(fuzz::text_of(data, size), '\0', 2);
  fuzz::input_file("model.bin", parts.size() > 1 ? parts[1] : std::string_view());
  const std::filesystem::path json = fuzz::input_file("model.json", parts[0]);
  bim::BimModel model;
  try {
    model = bim::read_import(json.string());
  } catch (const bim::BimError&) {
    return 0;
  }
  for (const bim::Element& e : model.elements) {
    for (const auto& t : e.mesh.triangles) {
      CONCERT_FUZZ_CHECK(t.minCoeff() >= 0 && t.maxCoeff() < static_cast<int>(e.mesh.vertices.size()),
                         "a triangle of element " + e.global_id + " beyond its vertices");
    }
  }
  for (const bim::Storey& s : model.storeys) {
    // Mapped only where the map stays small: slicing is linear in the map's cells, and the
    // fuzzer would spend its time drawing a 10 km storey (which storey_map does refuse past
    // 2e8 cells).
    Eigen::AlignedBox3d extent;
    for (const bim::Element* e : model.elements_of(s)) {
      if (!e->bounds.isEmpty()) extent.extend(e->bounds);
    }
    if (extent.isEmpty() || (extent.max() - extent.min()).head<2>().maxCoeff() > 200.0) continue;
    bim::SliceParams params;
    params.resolution = 0.25;
    try {
      const bim::OccupancyGrid grid = bim::storey_map(model, s, params);
      volatile int sink = grid.width + grid.height;
      (void)sink;
    } catch (const bim::BimError&) {
    }
  }
  return 0;
}

void concert::fuzz::write_seeds(SeedWriter& seeds) {
  seeds.add("two_walls.bin", two_walls());
  const std::filesystem::path out = input_file("placeholder", "").parent_path() / "import";
  bim::ImportOptions options;
  options.keep_dir = out.string();
  (void)bim::load_ifc((shared_data_dir() / "bim/IfcOpenHouse_IFC4.ifc").string(), options);
  seeds.add("ifcopenhouse.bin",
            file_bytes(out / "model.json") + std::string(1, '\0') + file_bytes(out / "model.bin"));
  seeds.add_tokens(kJsonTokens);
  seeds.add_tokens({"concert-ifc-import", "binary", "vertex_count", "index_count", "storeys",
                    "elements", "global_id", "ifc_type", "category", "storey_from", "placement",
                    "vertex_offset", "index_offset", "model.bin", "wall", "door", "slab"});
}
