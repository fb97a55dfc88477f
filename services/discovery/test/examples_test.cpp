// The scans shipped with the discovery service are what the simulated bus produces for their
// assemblies.
#include <gtest/gtest.h>

#include <string>

#include "concert/simbus/assembly.hpp"
#include "concert/topology/reconstruction.hpp"
#include "concert/topology/scan_io.hpp"

namespace concert::discovery {
namespace {

TEST(Discovery, ShippedExampleScansMatchTheirAssemblies) {
  const topology::EscCatalog catalog =
      topology::EscCatalog::load(std::string(CONCERT_SHARED_DATA) + "/concert_resources");
  const std::string examples = std::string(CONCERT_SOURCE_DIR) + "/libs/simbus/examples";
  const std::string dir = std::string(CONCERT_SOURCE_DIR) + "/services/discovery/examples";
  EXPECT_EQ(topology::discover(topology::load_scan(dir + "/paper_robot_scan.yaml"), catalog),
            simbus::tree_from_assembly(
                simbus::load_assembly(examples + "/concert_paper_robot.yaml"), catalog));
  EXPECT_EQ(topology::discover(topology::load_scan(dir + "/torso_two_arms_scan.json"), catalog),
            simbus::tree_from_assembly(
                simbus::load_assembly(examples + "/concert_torso_two_arms.yaml"), catalog));
}

}  // namespace
}  // namespace concert::discovery
