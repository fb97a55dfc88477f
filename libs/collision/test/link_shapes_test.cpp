// The collision model of libs/collision on the demo drill robot (generated from the project's
// module database by model generation, as the services receive it).
#include <gtest/gtest.h>

#include <algorithm>
#include <set>
#include <string>

#include "concert/collision/link_shapes.hpp"
#include "model_fixture.hpp"

namespace concert::collision {
namespace {

std::shared_ptr<const model::RobotModel> drill_robot() {
  return testing::robot_model(std::string(CONCERT_SOURCE_DIR) + "/deploy/demo/drill_robot.yaml");
}

TEST(RigidGroups, StartAtEachListedJointAndFollowFixedChildren) {
  const auto m = drill_robot();
  const auto& arm = m->arm().joints;
  const std::vector<int> g = rigid_groups(*m, arm);
  ASSERT_EQ(g.size(), m->links().size());
  int arm_links = 0;
  for (std::size_t l = 0; l < g.size(); ++l) {
    const model::Link& link = m->links()[l];
    const bool listed = link.moving && std::find(arm.begin(), arm.end(), link.joint) != arm.end();
    if (listed) {
      EXPECT_EQ(g[l], static_cast<int>(l)) << link.name;
      ++arm_links;
    } else if (link.parent < 0) {
      EXPECT_EQ(g[l], -1) << link.name;
    } else {
      EXPECT_EQ(g[l], g[static_cast<std::size_t>(link.parent)]) << link.name << " (joint " << link.joint << ")";
    }
  }
  EXPECT_EQ(arm_links, static_cast<int>(arm.size()));
  // The legs' joints are not listed: wheels and steering move with the root.
  for (const model::Leg& leg : m->legs()) {
    for (const model::Link& link : m->links()) {
      if (link.joint == leg.wheel_joint || link.joint == leg.steering_joint) {
        EXPECT_EQ(g[static_cast<std::size_t>(m->link_index(link.name))], -1) << link.name;
      }
    }
  }
}

// The paper's morphology B from the public CONCERT module database (its modules carry mesh
// collision geometry besides primitives).
std::shared_ptr<const model::RobotModel> public_morphology_b() {
  return testing::robot_model(
      std::string(CONCERT_SOURCE_DIR) + "/services/surface_finish/test/fixtures/morphology_b_spraying_public.yaml", 1,
      testing::public_module_db());
}

TEST(LinkShapes, LeavesOutEveryMeshOfThePublicDatabaseAndNamesItsLink) {
  const auto m = public_morphology_b();
  const LinkShapes shapes(*m, rigid_groups(*m, m->arm().joints));
  std::size_t meshes = 0, primitives = 0;
  for (const model::Link& link : m->links()) {
    for (const model::CollisionShape& c : link.shapes) {
      if (c.type == model::CollisionShape::Type::kMesh) {
        ++meshes;
        EXPECT_NE(std::find(shapes.ignored().begin(), shapes.ignored().end(), link.name + ": mesh"), shapes.ignored().end())
            << link.name;
      } else {
        ++primitives;
      }
    }
  }
  EXPECT_GT(meshes, 0u) << "the public modules carry meshes";
  EXPECT_EQ(shapes.ignored().size(), meshes);
  EXPECT_EQ(shapes.shapes().size(), primitives);
  for (const Shape& s : shapes.shapes()) EXPECT_NE(s.primitive.type, model::CollisionShape::Type::kMesh);
}

TEST(LinkShapes, ChecksEveryPairThatMovesAgainstEachOtherAndNoOther) {
 // The drill robot's modules are primitives; the public database's mostly meshes.
 for (const auto& [m, at_least] : {std::pair{drill_robot(), 10u}, std::pair{public_morphology_b(), 5u}}) {
  const std::vector<int> g = rigid_groups(*m, m->arm().joints);
  const LinkShapes shapes(*m, g, 0.02);
  ASSERT_GE(shapes.shapes().size(), at_least);
  const std::set<std::pair<int, int>> disabled(m->disabled_pairs().begin(), m->disabled_pairs().end());
  const std::set<std::pair<int, int>> checked(shapes.pairs().begin(), shapes.pairs().end());
  std::size_t expected = 0;
  for (std::size_t a = 0; a < shapes.shapes().size(); ++a) {
    for (std::size_t b = a + 1; b < shapes.shapes().size(); ++b) {
      const int la = std::min(shapes.shapes()[a].link, shapes.shapes()[b].link);
      const int lb = std::max(shapes.shapes()[a].link, shapes.shapes()[b].link);
      const bool moves = g[static_cast<std::size_t>(la)] != g[static_cast<std::size_t>(lb)];
      const bool wanted = moves && disabled.count({la, lb}) == 0;
      EXPECT_EQ(checked.count({static_cast<int>(a), static_cast<int>(b)}) > 0, wanted)
          << m->links()[static_cast<std::size_t>(la)].name << " / " << m->links()[static_cast<std::size_t>(lb)].name;
      expected += wanted ? 1 : 0;
    }
  }
  EXPECT_EQ(shapes.pairs().size(), expected);
  EXPECT_GT(expected, 0u);
 }
}

TEST(LinkShapes, FindsTwoLinksPlacedOntoEachOtherAndNothingWhenApart) {
  const auto m = drill_robot();
  LinkShapes shapes(*m, rigid_groups(*m, m->arm().joints));
  ASSERT_FALSE(shapes.pairs().empty());
  // Every link 10 m from every other: nothing touches.
  std::vector<Eigen::Isometry3d> poses(m->links().size(), Eigen::Isometry3d::Identity());
  for (std::size_t l = 0; l < poses.size(); ++l) poses[l].translation().x() = 10.0 * static_cast<double>(l);
  shapes.place(poses);
  EXPECT_FALSE(shapes.self_collision());
  // The shapes of the last checked pair made to coincide: that pair, and only that one, is found.
  const auto [a, b] = shapes.pairs().back();
  const Shape& sa = shapes.shapes()[static_cast<std::size_t>(a)];
  const Shape& sb = shapes.shapes()[static_cast<std::size_t>(b)];
  poses[static_cast<std::size_t>(sb.link)] =
      poses[static_cast<std::size_t>(sa.link)] * sa.primitive.origin * sb.primitive.origin.inverse();
  shapes.place(poses);
  const auto hit = shapes.self_collision();
  ASSERT_TRUE(hit);
  EXPECT_EQ(*hit, std::make_pair(std::min(sa.link, sb.link), std::max(sa.link, sb.link)));
}

TEST(LinkShapes, PadsEverySideOfTheClearanceCopy) {
  const auto m = drill_robot();
  const double pad = 0.05;
  LinkShapes shapes(*m, rigid_groups(*m, m->arm().joints), pad);
  shapes.place(std::vector<Eigen::Isometry3d>(m->links().size(), Eigen::Isometry3d::Identity()));
  int boxes = 0;
  for (std::size_t i = 0; i < shapes.shapes().size(); ++i) {
    const Shape& s = shapes.shapes()[i];
    if (s.primitive.type != model::CollisionShape::Type::kBox) continue;
    const auto exact = shapes.exact(i).getAABB();
    const auto padded = shapes.padded(i).getAABB();
    const bool aligned = s.primitive.origin.linear().isIdentity(1e-12);
    for (int k = 0; k < 3; ++k) {
      EXPECT_LT(padded.min_[k], exact.min_[k]) << "shape " << i;
      EXPECT_GT(padded.max_[k], exact.max_[k]) << "shape " << i;
      if (aligned) {  // an axis-aligned box: each face exactly `pad` further out
        EXPECT_NEAR(exact.min_[k] - padded.min_[k], pad, 1e-9) << "shape " << i;
        EXPECT_NEAR(padded.max_[k] - exact.max_[k], pad, 1e-9) << "shape " << i;
      }
    }
    boxes += aligned ? 1 : 0;
  }
  EXPECT_GT(boxes, 0);
  EXPECT_THROW(LinkShapes(*m, {}, 0.0), std::invalid_argument);
  EXPECT_THROW(LinkShapes(*m, rigid_groups(*m, {}), -0.1), std::invalid_argument);
}

TEST(LinkShapes, PadsABitSidewaysAndBackwardsButNotBeyondItsTip) {
  const auto m = drill_robot();
  const double pad = 0.03;
  // A bit 0.1 m long on the last link, its tip (+z end) at the link's origin.
  model::CollisionShape bit;
  bit.type = model::CollisionShape::Type::kCylinder;
  bit.size = {0.008, 0.008, 0.1};
  bit.origin = Eigen::Translation3d(0.0, 0.0, -0.05) * Eigen::Isometry3d::Identity();
  const int link = static_cast<int>(m->links().size()) - 1;
  LinkShapes shapes(*m, rigid_groups(*m, m->arm().joints), pad, {{link, {bit}}});
  shapes.place(std::vector<Eigen::Isometry3d>(m->links().size(), Eigen::Isometry3d::Identity()));
  const auto found = std::find_if(shapes.shapes().begin(), shapes.shapes().end(), [&](const Shape& s) {
    return s.link == link && s.primitive.type == model::CollisionShape::Type::kCylinder &&
           s.primitive.size.isApprox(bit.size);
  });
  ASSERT_NE(found, shapes.shapes().end());
  const std::size_t i = static_cast<std::size_t>(found - shapes.shapes().begin());
  const auto exact = shapes.exact(i).getAABB();
  const auto padded = shapes.padded(i).getAABB();
  EXPECT_NEAR(exact.max_.z(), 0.0, 1e-9);
  EXPECT_NEAR(exact.min_.z(), -0.1, 1e-9);
  EXPECT_NEAR(padded.max_.z(), 0.0, 1e-9) << "the tip is not padded";
  EXPECT_NEAR(padded.min_.z(), -0.1 - pad, 1e-9) << "the back is";
  for (int k = 0; k < 2; ++k) {
    EXPECT_NEAR(padded.max_[k] - exact.max_[k], pad, 1e-9) << "sideways, axis " << k;
    EXPECT_NEAR(exact.min_[k] - padded.min_[k], pad, 1e-9) << "sideways, axis " << k;
  }
  // The padded shape's radius about its own centre, half-way along it.
  EXPECT_NEAR(shapes.padded(i).getTranslation().z(), -0.5 * (0.1 + pad), 1e-9);
  EXPECT_NEAR(found->padded_radius, std::hypot(0.008 + pad, 0.5 * (0.1 + pad)), 1e-12);
}

}  // namespace
}  // namespace concert::collision
