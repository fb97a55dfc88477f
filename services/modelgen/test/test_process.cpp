// concert_modelgen as a real process: a tree published by this test comes back as a latched
// GeneratedModel; the process deploys the bundle and stops cleanly on SIGTERM.

#include <gtest/gtest.h>
#include <signal.h>
#include <sys/wait.h>
#include <unistd.h>

#include <chrono>
#include <filesystem>
#include <thread>

#include "concert/dds/endpoint.hpp"
#include "concert/dds/participant.hpp"
#include "concert/topology/dds/conversions.hpp"
#include "modelgen/bundle.hpp"

namespace fs = std::filesystem;
using namespace std::chrono_literals;

TEST(ModelgenProcess, TreeInModelOutCleanStop) {
  const fs::path bundle = fs::temp_directory_path() / ("concert_modelgen_process_" + std::to_string(::getpid()));
  fs::remove_all(bundle);
  const std::string exe = CONCERT_MODELGEN_EXE;
  const std::string db = (fs::path(CONCERT_SHARED_DATA) / "concert_resources").string();
  const pid_t pid = ::fork();
  ASSERT_GE(pid, 0);
  if (pid == 0) {
    ::execl(exe.c_str(), exe.c_str(), "--module-db", db.c_str(), "--bundle", bundle.c_str(), static_cast<char*>(nullptr));
    ::_exit(127);
  }
  {
    concert::dds::Participant p({.name = "modelgen_process_test"});
    concert::dds::Writer<concert::msg::ModuleTree> trees(p, concert::dds::topics::module_tree);
    concert::dds::Reader<concert::msg::RobotModel> models(p, concert::dds::topics::robot_model);
    ASSERT_TRUE(trees.wait_for_readers(1, 20000ms)) << "concert_modelgen did not come up";
    concert::topology::ModuleTree tree;
    const char* keys[] = {"mobile_platform_concert", "module_joint_yaw_A_concert", "module_joint_elbow_A_concert", "module_drill_concert"};
    for (int i = 0; i < 4; ++i) {
      concert::topology::ModuleNode n;
      n.index = i;
      n.key = keys[i];
      n.parent_module = i - 1;
      n.parent_connector = i == 0 ? -1 : i == 1 ? 5 : 1;
      tree.modules.push_back(n);
    }
    ASSERT_TRUE(trees.write(concert::topology::dds::to_msg(tree, 4, 0, 0)));
    const auto model = models.wait(20000ms);
    ASSERT_TRUE(model.has_value());
    EXPECT_EQ(model->version(), 1u);
    EXPECT_EQ(model->tree_version(), 4u);
    ASSERT_EQ(model->end_effectors().size(), 1u);
    EXPECT_EQ(model->end_effectors()[0].name(), "drill_A");
    // The bundle on disk is the same model.
    for (int i = 0; i < 100 && concert::modelgen::read_bundle_version(bundle).second != model->content_hash(); ++i) {
      std::this_thread::sleep_for(20ms);
    }
    EXPECT_EQ(concert::modelgen::read_bundle_version(bundle).second, model->content_hash());
  }
  ASSERT_EQ(::kill(pid, SIGTERM), 0);
  int status = 0;
  pid_t done = 0;
  for (int i = 0; i < 200 && done == 0; ++i) {
    done = ::waitpid(pid, &status, WNOHANG);
    if (done == 0) std::this_thread::sleep_for(50ms);
  }
  if (done == 0) {
    ::kill(pid, SIGKILL);
    ::waitpid(pid, &status, 0);
    FAIL() << "concert_modelgen did not stop within 10 s of SIGTERM";
  }
  EXPECT_TRUE(WIFEXITED(status));
  EXPECT_EQ(WEXITSTATUS(status), 0);
  fs::remove_all(bundle);
}
