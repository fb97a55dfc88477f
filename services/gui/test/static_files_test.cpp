#include "gui/static_files.hpp"

#include <gtest/gtest.h>

#include <fstream>

namespace concert::gui {
namespace {

namespace fs = std::filesystem;

class StaticFiles : public testing::Test {
 protected:
  void SetUp() override {
    root_ = fs::temp_directory_path() / ("gui_static_" + std::to_string(::getpid()));
    fs::create_directories(root_ / "app" / "sub");
    fs::create_directories(root_ / "db" / "models");
    std::ofstream(root_ / "app" / "index.html") << "<html>";
    std::ofstream(root_ / "app" / "sub" / "a b.js") << "x";
    std::ofstream(root_ / "db" / "models" / "m.stl") << "solid";
    std::ofstream(root_ / "secret.txt") << "no";
    fs::create_symlink(root_ / "secret.txt", root_ / "app" / "link.txt");
    roots_.app = root_ / "app";
    roots_.packages["concert_resources"] = root_ / "db";
  }
  void TearDown() override { fs::remove_all(root_); }
  fs::path root_;
  StaticRoots roots_;
};

TEST_F(StaticFiles, ServesTheAppAndPackages) {
  EXPECT_EQ(resolve_request(roots_, "/")->filename(), "index.html");
  EXPECT_EQ(resolve_request(roots_, "/index.html?v=3")->filename(), "index.html");
  EXPECT_EQ(resolve_request(roots_, "/sub/a%20b.js")->filename(), "a b.js");
  EXPECT_EQ(resolve_request(roots_, "/packages/concert_resources/models/m.stl")->filename(), "m.stl");
}

TEST_F(StaticFiles, NothingOutsideItsRoots) {
  EXPECT_FALSE(resolve_request(roots_, "/../secret.txt"));
  EXPECT_FALSE(resolve_request(roots_, "/sub/%2e%2e/%2e%2e/secret.txt"));
  EXPECT_FALSE(resolve_request(roots_, "/link.txt"));  // a symbolic link out of the app
  EXPECT_FALSE(resolve_request(roots_, "/packages/concert_resources/../secret.txt"));
  EXPECT_FALSE(resolve_request(roots_, "/packages/other/models/m.stl"));
  EXPECT_FALSE(resolve_request(roots_, "/nope.js"));
  EXPECT_FALSE(resolve_request(roots_, "/bad%zz"));
  EXPECT_FALSE(resolve_request(roots_, "relative"));
}

TEST(MimeType, ByExtension) {
  EXPECT_EQ(mime_type("a/b.JS"), "text/javascript; charset=utf-8");
  EXPECT_EQ(mime_type("m.stl"), "model/stl");
  EXPECT_EQ(mime_type("x.bin"), "application/octet-stream");
  EXPECT_EQ(package_of("/data/concert_resources/").first, "concert_resources");
}

}  // namespace
}  // namespace concert::gui
