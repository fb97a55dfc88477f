#include <filesystem>

#include <gtest/gtest.h>

#include "modelgen/bundle.hpp"
#include "modelgen/service.hpp"
#include "test_support.hpp"

namespace fs = std::filesystem;
using namespace concert;
using namespace concert::modelgen;

namespace {

const module_db::ModuleDatabase& public_db() {
  static const module_db::ModuleDatabase db = module_db::load_module_database(fs::path(CONCERT_SHARED_DATA) / "concert_resources");
  return db;
}

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
  EXPECT_NE(o.error.find("outside the limits"), std::string::npos);
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
