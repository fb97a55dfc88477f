#include <filesystem>

#include <gmock/gmock.h>
#include <gtest/gtest.h>

#include "modelgen/bundle.hpp"
#include "modelgen/service.hpp"
#include "test_support.hpp"

namespace fs = std::filesystem;
using namespace concert;
using namespace concert::modelgen;
using concert::modelgen::test::public_db;

namespace {

using ::testing::HasSubstr;

}  // namespace

TEST(Service, TreesCustomisationsAndErrors) {
  ModelgenService service(public_db());
  const auto big = test::make_tree(test::public_eighteen_module_robot(), &public_db());
  EXPECT_EQ(service.on_customisation({1, 0, {}}).error, "customisation request 1: no module tree yet");
  Outcome o = service.on_tree(big, 7);
  EXPECT_TRUE(o.published);
  EXPECT_EQ(o.version, 1u);
  EXPECT_EQ(service.current()->tree_version, 7u);
  o = service.on_tree(big, 8);  // same robot: no new version
  EXPECT_FALSE(o.published);
  EXPECT_EQ(o.version, 1u);
  EXPECT_TRUE(o.error.empty());
  // Bad tree: error, model kept.
  o = service.on_tree(test::make_tree({{"mobile_platform_concert", -1, -1}, {"nope", 0, 5}}), 9);
  EXPECT_FALSE(o.published);
  EXPECT_EQ(o.version, 1u);
  EXPECT_EQ(o.error, "tree 9: module 1 ('nope'): no module description with key 'nope' in the module database");
  EXPECT_EQ(service.current()->tree_version, 8u);
  // Customisation: stale base version refused, valid one publishes version 2.
  CustomisationRequest r{2, 5, {}};
  r.customisation.home["J1_E"] = 0.25;
  EXPECT_EQ(service.on_customisation(r).error, "customisation request 2: made for model version 5 but the current version is 1");
  r.base_version = 1;
  o = service.on_customisation(r);
  EXPECT_TRUE(o.published) << o.error;
  EXPECT_EQ(o.version, 2u);
  EXPECT_DOUBLE_EQ(service.current()->joints[8].home, 0.25);
  // A bad request keeps version 2 and the old customisation.
  CustomisationRequest bad{3, 0, {}};
  bad.customisation.home["J1_E"] = 99.0;
  o = service.on_customisation(bad);
  EXPECT_FALSE(o.published);
  EXPECT_EQ(o.version, 2u);
  EXPECT_THAT(o.error, HasSubstr("outside the limits"));
  EXPECT_DOUBLE_EQ(service.customisation().home.at("J1_E"), 0.25);
  // A new tree without J1_E drops the customisation instead of failing.
  o = service.on_tree(test::make_tree({{"mobile_platform_concert", -1, -1}}, &public_db()), 10);
  EXPECT_TRUE(o.published) << o.error;
  EXPECT_EQ(o.version, 3u);
  EXPECT_TRUE(service.customisation().home.empty());
}

TEST(Service, BundleVersionsContinueAcrossRestarts) {
  const fs::path dir = fs::temp_directory_path() / ("concert_modelgen_service_" + std::to_string(::getpid()));
  fs::remove_all(dir);
  const auto big = test::make_tree(test::public_eighteen_module_robot(), &public_db());
  // Named rather than {{}, dir}: GCC 12 at -O3 warns (maybe-uninitialized) on that temporary.
  ServiceParams params;
  params.bundle_dir = dir;
  {
    ModelgenService s(public_db(), params);
    EXPECT_EQ(s.on_tree(big, 1).version, 1u);
  }
  EXPECT_EQ(read_bundle_version(dir).first, 1u);
  ModelgenService restarted(public_db(), params);
  const Outcome same = restarted.on_tree(big, 1);
  EXPECT_TRUE(same.published);  // nobody has it yet after the restart
  EXPECT_EQ(same.version, 1u);  // same content, same version
  const Outcome other = restarted.on_tree(test::make_tree({{"mobile_platform_concert", -1, -1}}, &public_db()), 2);
  EXPECT_EQ(other.version, 2u);
  EXPECT_EQ(read_bundle_version(dir).first, 2u);
  fs::remove_all(dir);
}

TEST(Service, UnknownModulesAreRefusedByPositionAndIdentityAndTheModelStays) {
  ModelgenService service(public_db());
  auto tree = test::make_tree(test::public_eighteen_module_robot(), &public_db());
  for (std::size_t i = 0; i < tree.modules.size(); ++i) {
    tree.modules[i].slave_positions = {static_cast<int32_t>(i) + 1};
  }
  ASSERT_TRUE(service.on_tree(tree, 1).published);
  const std::string hash = service.current()->content_hash;
  // Two boards discovery could not identify: one with an all-zero identity, one unknown.
  auto unknown = tree;
  unknown.modules[4].known = false;
  unknown.modules[4].key.clear();
  unknown.modules[4].identity = {};
  unknown.modules[12].known = false;
  unknown.modules[12].key.clear();
  unknown.modules[12].identity = {1, 99, 4, 0};
  const Outcome o = service.on_tree(unknown, 2);
  EXPECT_FALSE(o.published);
  EXPECT_EQ(o.version, 1u);
  EXPECT_EQ(
      o.error,
      "tree 2: the module tree has 2 unknown modules, not in the ESC catalogue of the module "
      "database: slave 5 (mod_type 0, mod_id 0, mod_size 0, mod_rev 0); slave 13 (mod_type 1, "
      "mod_id 99, mod_size 4, mod_rev 0); no model is built until every module is known");
  EXPECT_EQ(service.current()->content_hash, hash);
  // A tree with errors (undefined) is refused too, whatever the database.
  auto undefined = tree;
  undefined.issues.push_back(
      {topology::TreeIssue::Severity::kError, 7, "port 1 is open but no slave hangs on it"});
  EXPECT_NE(service.on_tree(undefined, 3).error.find("1 error (slave 7: port 1 is open"),
            std::string::npos);
  // Warnings alone do not stop a model.
  auto warned = tree;
  warned.issues.push_back(
      {topology::TreeIssue::Severity::kWarning, 3, "topology says 3 open ports"});
  EXPECT_TRUE(service.on_tree(warned, 4).error.empty());
  EXPECT_EQ(service.current()->content_hash, hash);
}

TEST(Service, ARestartLearnsTheRunningModelAndNeverReusesAVersion) {
  const auto big = test::make_tree(test::public_eighteen_module_robot(), &public_db());
  const auto small = test::make_tree({{"mobile_platform_concert", -1, -1}}, &public_db());
  // The first incarnation: version 1 (big), version 2 (small).
  ModelgenService first(public_db());
  ASSERT_EQ(first.on_tree(big, 1).version, 1u);
  ASSERT_EQ(first.on_tree(small, 2).version, 2u);
  const std::string running = first.current()->content_hash;

  // Restarted without a bundle: the services on the wire say they run version 2 with that hash.
  ModelgenService restarted(public_db());
  restarted.learn(2, running);
  EXPECT_EQ(restarted.known_version(), 2u);
  Outcome o = restarted.on_tree(small, 2);  // the latched tree: the running model again
  EXPECT_TRUE(o.published);
  EXPECT_EQ(o.version, 2u);
  EXPECT_EQ(restarted.current()->content_hash, running);
  o = restarted.on_tree(big, 3);  // the next hot swap: a new, higher version
  EXPECT_EQ(o.version, 3u);

  // Restarted, and the latched tree already differs from what runs: never version 2 again.
  ModelgenService other(public_db());
  other.learn(2, running);
  EXPECT_EQ(other.on_tree(big, 3).version, 3u);

  // Older knowledge (a stale bundle, a lagging service) changes nothing.
  ModelgenService late(public_db());
  late.learn(2, running);
  late.learn(1, "sha256:older");
  EXPECT_EQ(late.on_tree(small, 2).version, 2u);
}
