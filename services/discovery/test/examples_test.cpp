// The scans shipped with the discovery service are what the simulated bus produces for their
// assemblies.
#include <gtest/gtest.h>

#include <string>

#include "concert/simbus/assembly.hpp"
#include "concert/topology/reconstruction.hpp"
#include "concert/topology/scan_io.hpp"
#include "test_data.hpp"

namespace concert::discovery {
namespace {

TEST(Discovery, ShippedExampleScansMatchTheirAssemblies) {
  using test_data::kExamples;
  const topology::EscCatalog catalog = topology::EscCatalog::load(test_data::kPublicDb);
  const std::string dir = std::string(CONCERT_SOURCE_DIR) + "/services/discovery/examples";
  EXPECT_EQ(topology::discover(topology::load_scan(dir + "/paper_robot_scan.yaml"), catalog),
            simbus::tree_from_assembly(
                simbus::load_assembly(kExamples + "/concert_paper_robot.yaml"), catalog));
  EXPECT_EQ(topology::discover(topology::load_scan(dir + "/torso_two_arms_scan.json"), catalog),
            simbus::tree_from_assembly(
                simbus::load_assembly(kExamples + "/concert_torso_two_arms.yaml"), catalog));
}

}  // namespace
}  // namespace concert::discovery
