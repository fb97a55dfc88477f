#include <gmock/gmock.h>
#include <gtest/gtest.h>

#include <algorithm>
#include <cctype>
#include <filesystem>
#include <fstream>

#include "bim_test_models.hpp"
#include "concert/bim/geometry.hpp"
#include "process.hpp"

namespace concert::bim {
namespace {

namespace fs = std::filesystem;
using ::testing::HasSubstr;
using namespace concert::bim::test_models;

/// Every IFC type the import knows, as the file spells it.
const std::vector<std::string> kTypes = {"IFCWALL",
                                         "IFCWALLSTANDARDCASE",
                                         "IFCWALLELEMENTEDCASE",
                                         "IFCCURTAINWALL",
                                         "IFCDOOR",
                                         "IFCWINDOW",
                                         "IFCCOLUMN",
                                         "IFCSLAB",
                                         "IFCSTAIR",
                                         "IFCSTAIRFLIGHT",
                                         "IFCRAMP",
                                         "IFCRAMPFLIGHT",
                                         "IFCRAILING",
                                         "IFCCOVERING",
                                         "IFCFURNISHINGELEMENT",
                                         "IFCFURNITURE",
                                         "IFCBEAM",
                                         "IFCMEMBER",
                                         "IFCPLATE",
                                         "IFCROOF",
                                         "IFCBUILDINGELEMENTPROXY"};

std::map<std::string, int> imported_counts(const BimModel& m) {
  std::map<std::string, int> counts;
  for (const auto& e : m.elements) {
    std::string t = e.ifc_type;
    std::transform(t.begin(), t.end(), t.begin(), [](unsigned char c) { return std::toupper(c); });
    ++counts[t];
  }
  return counts;
}

class SharedFiles : public ::testing::TestWithParam<std::string> {};

TEST_P(SharedFiles, ElementCountsPerTypeMatchTheFile) {
  const BimModel& m = shared_model(GetParam());
  const std::string text = file_text(bim_file(GetParam()));
  const auto counts = imported_counts(m);
  int checked = 0;
  for (const auto& type : kTypes) {
    const int truth = count_entities(text, type);
    const auto it = counts.find(type);
    EXPECT_EQ(it == counts.end() ? 0 : it->second, truth) << GetParam() << ": " << type;
    checked += truth;
  }
  EXPECT_GT(checked, 20);
  EXPECT_EQ(static_cast<int>(m.elements.size()), checked);
}

TEST_P(SharedFiles, EveryElementHasAStoreyAndEveryWallAMeshInMetres) {
  const BimModel& m = shared_model(GetParam());
  for (const auto& e : m.elements) {
    EXPECT_NO_THROW((void)m.storey(e.storey)) << e.global_id;
    EXPECT_EQ(e.global_id.size(), 22u) << e.global_id;
    if (e.category != Category::kWall) continue;
    ASSERT_FALSE(e.mesh.triangles.empty()) << e.global_id;
    // Metres: a wall of a house is between 5 cm and 30 m long, 0.1 .. 10 m high (a parapet is low).
    const Eigen::Vector3d size = e.bounds.sizes();
    EXPECT_LT(size.head<2>().maxCoeff(), 30.0) << e.global_id;
    EXPECT_GT(size.head<2>().maxCoeff(), 0.05) << e.global_id;
    EXPECT_GT(size.z(), 0.1) << e.global_id;
    EXPECT_LT(size.z(), 10.0) << e.global_id;
  }
}

INSTANTIATE_TEST_SUITE_P(Bim, SharedFiles,
                         ::testing::Values("AC20-FZK-Haus.ifc", "duplex.ifc",
                                           "IfcOpenHouse_IFC4.ifc"),
                         [](const auto& p) {
                           std::string n = p.param.substr(0, p.param.find('.'));
                           std::replace(n.begin(), n.end(), '-', '_');
                           return n;
                         });

TEST(Import, DuplexHas57WallsAndFourStoreysZUp) {
  const BimModel& m = shared_model("duplex.ifc");
  EXPECT_EQ(m.schema, "IFC2X3");
  EXPECT_EQ(std::count_if(m.elements.begin(), m.elements.end(),
                          [](const Element& e) { return e.category == Category::kWall; }),
            57);
  std::vector<std::string> names;
  for (const auto& s : m.storeys) names.push_back(s.name);
  EXPECT_THAT(names, ::testing::ElementsAre("T/FDN", "Level 1", "Level 2", "Roof"));
  EXPECT_NEAR(m.storey("Level 2").elevation, 3.1, 1e-6);
  EXPECT_NEAR(m.storey("T/FDN").elevation, -1.25, 1e-6);
  // Z up: the walls of Level 2 are above its floor, most of them standing on it (the others are
  // parapets on the roof).
  int standing = 0;
  int walls = 0;
  for (const Element* e : m.elements_of(m.storey("Level 2"))) {
    if (e->category != Category::kWall) continue;
    ++walls;
    EXPECT_GT(e->bounds.min().z(), 3.1 - 0.6) << e->global_id;
    standing += std::abs(e->bounds.min().z() - 3.1) < 0.6 ? 1 : 0;
  }
  EXPECT_GT(walls, 20);
  EXPECT_GT(standing, walls * 2 / 3);
}

TEST(Import, FzkHausStoreysAndLengthUnit) {
  const BimModel& m = shared_model("AC20-FZK-Haus.ifc");
  EXPECT_EQ(m.schema, "IFC4");
  ASSERT_EQ(m.storeys.size(), 2u);
  EXPECT_EQ(m.storeys[0].name, "Erdgeschoss");
  EXPECT_EQ(m.storeys[1].name, "Dachgeschoss");
  EXPECT_NEAR(m.storeys[1].elevation, 2.7, 1e-6);
  EXPECT_EQ(m.storey("273g3wqLzDtfYIl7qqkgcO").name, "Dachgeschoss");  // by GlobalId too
}

TEST(Import, MillimetreFileComesOutInMetres) {
  const BimModel& m = shared_model("IfcOpenHouse_IFC4.ifc");
  EXPECT_DOUBLE_EQ(m.length_unit_m, 0.001);
  ASSERT_EQ(m.storeys.size(), 1u);
  Eigen::AlignedBox3d all;
  for (const auto& e : m.elements) {
    if (e.category == Category::kWall) all.extend(e.bounds);
  }
  // The IfcOpenHouse is about 10 x 5 m with 3 m walls.
  EXPECT_NEAR(all.sizes().x(), 10.0, 1.0);
  EXPECT_GT(all.sizes().z(), 2.0);
  EXPECT_LT(all.sizes().z(), 6.0);
}

TEST(Import, DoorsFillOpeningsOfTheirHostWall) {
  const BimModel& m = shared_model("AC20-FZK-Haus.ifc");
  int doors = 0;
  for (const auto& d : m.elements) {
    if (d.category != Category::kDoor) continue;
    ++doors;
    ASSERT_FALSE(d.host.empty()) << d.global_id;
    const Element& wall = m.element(d.host);
    ASSERT_EQ(wall.category, Category::kWall);
    // No wall triangle has a vertex strictly inside the door's box (the opening is cut).
    Eigen::AlignedBox3d inner = d.bounds;
    inner.min() += Eigen::Vector3d(0.05, 0.05, 0.05);
    inner.max() -= Eigen::Vector3d(0.05, 0.05, 0.05);
    const Eigen::Vector3d mid = d.bounds.center();
    const WallGeometry g = wall_geometry(wall);
    const Eigen::Vector2d dir = g.direction();
    const double along = dir.dot(mid.head<2>() - g.start);
    // The wall's vertices at the door's mid height along its axis: none within the door's width.
    for (const auto& v : wall.mesh.vertices) {
      if (std::abs(v.z() - mid.z()) > 0.05) continue;
      const double s = dir.dot(v.head<2>() - g.start);
      const Eigen::Vector2d half = d.bounds.sizes().head<2>() / 2;
      const double half_width = std::abs(dir.x()) * half.x() + std::abs(dir.y()) * half.y();
      EXPECT_FALSE(std::abs(s - along) < half_width - 0.15)
          << d.global_id << " in " << wall.global_id;
    }
  }
  EXPECT_EQ(doors, 5);
}

class BadInput : public ::testing::Test {
 protected:
  std::string write(const std::string& name, const std::string& content) {
    const fs::path p = fs::path(dir_.path()) / name;
    std::ofstream(p, std::ios::binary) << content;
    return p.string();
  }
  /// load_ifc(path) fails with a message naming the file and saying `what`.
  static void expect_refused(const std::string& path, const std::string& what) {
    EXPECT_THAT([&] { (void)load_ifc(path); }, ::testing::ThrowsMessage<BimError>(::testing::AllOf(
                                                   HasSubstr(path), HasSubstr(what))));
  }
  concert::testing::TempDir dir_{"bim-test"};
};

TEST_F(BadInput, TruncatedFileIsNamed) {
  const std::string text = file_text(bim_file("duplex.ifc"));
  expect_refused(write("truncated.ifc", text.substr(0, text.size() / 2)), "truncated");
}

TEST_F(BadInput, NonIfcFileIsNamed) {
  expect_refused(write("notes.ifc", "these are not the walls you are looking for\n"),
                 "not an IFC file");
}

TEST_F(BadInput, MissingFile) { expect_refused(dir_.path() + "/none.ifc", "no such file"); }

TEST_F(BadInput, BuildingWithoutWalls) {
  std::string text = file_text(bim_file("IfcOpenHouse_IFC4.ifc"));
  // The same house with its walls turned into proxies.
  text = std::regex_replace(text, std::regex("IFCWALLSTANDARDCASE\\("), "IFCBUILDINGELEMENTPROXY(");
  const std::string path = write("no_walls.ifc", text);
  EXPECT_THAT([&] { (void)load_ifc(path); },
              ::testing::ThrowsMessage<BimError>(HasSubstr("no walls")));
}

TEST_F(BadInput, MissingImportStepIsNamed) {
  EXPECT_THAT(
      [&] { (void)load_ifc(bim_file("duplex.ifc"), {.script = dir_.path() + "/nope.mjs"}); },
      ::testing::ThrowsMessage<BimError>(HasSubstr("nope.mjs")));
}

TEST(Lookup, UnknownStoreyListsTheStoreys) {
  const BimModel& m = shared_model("AC20-FZK-Haus.ifc");
  EXPECT_THAT([&] { (void)m.storey("Keller"); },
              ::testing::ThrowsMessage<BimError>(
                  HasSubstr("storey 'Keller' not found in " + bim_file("AC20-FZK-Haus.ifc") +
                            "; storeys: Erdgeschoss, Dachgeschoss")));
}

TEST(Lookup, UnknownGlobalId) {
  const BimModel& m = shared_model("duplex.ifc");
  EXPECT_THAT([&] { (void)m.element("0000000000000000000000"); },
              ::testing::ThrowsMessage<BimError>(
                  HasSubstr("no element with GlobalId '0000000000000000000000'")));
}

TEST(Slug, FileNameSafe) {
  EXPECT_EQ(slug("Level 1"), "level-1");
  EXPECT_EQ(slug("T/FDN"), "t-fdn");
  EXPECT_EQ(slug("Erdgeschoss"), "erdgeschoss");
  EXPECT_EQ(slug("//"), "storey");
}

}  // namespace
}  // namespace concert::bim
