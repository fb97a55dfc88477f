#include "concert/bim/occupancy_grid.hpp"

#include <gmock/gmock.h>
#include <gtest/gtest.h>

#include <filesystem>
#include <fstream>
#include <random>

#include "process.hpp"

namespace concert::bim {
namespace {

namespace fs = std::filesystem;
using ::testing::HasSubstr;

class MapFiles : public ::testing::Test {
 protected:
  concert::testing::TempDir tmp_{"bim-map-test"};
  fs::path dir_{tmp_.path()};
};

TEST_F(MapFiles, RoundTripKeepsEveryCellAndTheFrame) {
  std::mt19937 rng(16);
  std::uniform_int_distribution<int> pick(0, 2);
  OccupancyGrid g = OccupancyGrid::filled(37, 23, 0.05, {-1.25, 3.5});
  for (auto& c : g.cells) {
    const int k = pick(rng);
    c = k == 0 ? OccupancyGrid::kFree : k == 1 ? OccupancyGrid::kOccupied : OccupancyGrid::kUnknown;
  }
  save_map(g, dir_.string(), "level-1");
  const OccupancyGrid back = load_map((dir_ / "level-1.yaml").string());
  EXPECT_EQ(back.width, 37);
  EXPECT_EQ(back.height, 23);
  EXPECT_DOUBLE_EQ(back.resolution, 0.05);
  EXPECT_NEAR((back.origin - g.origin).norm(), 0, 1e-9);
  EXPECT_EQ(back.cells, g.cells);
  // Row 0 is the bottom: the PGM's last row.
  EXPECT_EQ(back.cell_of(g.center_of(3, 0)), Eigen::Vector2i(3, 0));
}

TEST_F(MapFiles, MissingYamlIsNamed) {
  const std::string path = (dir_ / "none.yaml").string();
  EXPECT_THAT([&] { (void)load_map(path); }, ::testing::ThrowsMessage<MapError>(HasSubstr(path)));
}

TEST_F(MapFiles, MissingFieldIsNamed) {
  std::ofstream(dir_ / "map.yaml") << "image: map.pgm\norigin: [0, 0, 0]\n";
  EXPECT_THAT([&] { (void)load_map((dir_ / "map.yaml").string()); },
              ::testing::ThrowsMessage<MapError>(HasSubstr("resolution")));
}

TEST_F(MapFiles, BadImageIsNamed) {
  save_map(OccupancyGrid::filled(4, 4, 0.1, {0, 0}), dir_.string(), "map");
  std::ofstream(dir_ / "map.pgm", std::ios::binary) << "P5\n4 4\n255\nab";  // 2 of 16 pixels
  EXPECT_THAT([&] { (void)load_map((dir_ / "map.yaml").string()); },
              ::testing::ThrowsMessage<MapError>(HasSubstr("map.pgm")));
  std::ofstream(dir_ / "map.pgm", std::ios::binary) << "GIF89a";
  EXPECT_THAT([&] { (void)load_map((dir_ / "map.yaml").string()); },
              ::testing::ThrowsMessage<MapError>(HasSubstr("map.pgm")));
}

TEST(OccupancyGrid, BadSizesAreRefused) {
  EXPECT_THROW((void)OccupancyGrid::filled(0, 3, 0.05, {0, 0}), MapError);
  EXPECT_THROW((void)OccupancyGrid::filled(3, 3, 0.0, {0, 0}), MapError);
}

}  // namespace
}  // namespace concert::bim
