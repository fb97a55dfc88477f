// Params and world YAML: defaults, values read, and errors naming the file and field.

#include "planner/config.hpp"

#include <gtest/gtest.h>

#include <cmath>

using namespace concert::planner;

TEST(Config, ParamsReadAndDefaultsKept) {
  const Params p = parse_params("contact_force: 150\nplanning_time: 1.5\nseed: 9\nnspg_seeds: 12\n", "p.yaml");
  EXPECT_DOUBLE_EQ(p.contact_force, 150.0);
  EXPECT_DOUBLE_EQ(p.planning_time, 1.5);
  EXPECT_EQ(p.seed, 9u);
  EXPECT_EQ(p.nspg_seeds, 12);
  EXPECT_DOUBLE_EQ(p.camera_distance, Params{}.camera_distance);
}

TEST(Config, ShippedParamsFileListsEveryParameterWithItsDefault) {
  auto doc = concert::config::Document::load(std::string(CONCERT_SOURCE_DIR) +
                                             "/services/planner/config/planner.yaml");
  (void)read_params(doc);
  EXPECT_EQ(doc.keys().size(), 49u);  // every parameter of Params
  EXPECT_TRUE(doc.differences_from_defaults().empty())
      << ::testing::PrintToString(doc.differences_from_defaults());
}

TEST(Config, ParamErrorsNameFileAndField) {
  auto message = [](const std::string& yaml) {
    try {
      (void)parse_params(yaml, "p.yaml");
    } catch (const PlannerError& e) {
      return std::string(e.what());
    }
    return std::string("no error");
  };
  EXPECT_NE(
      message("bogus: 1")
          .find("p.yaml: bogus: unknown key (line 1); known keys: base_angular_acceleration,"),
      std::string::npos);
  EXPECT_EQ(message("seed: 2\ncontact_force: lots"),
            "p.yaml: contact_force: expected a number >= 0, got 'lots' (line 2)");
  EXPECT_EQ(message("planning_time: 0"),
            "p.yaml: planning_time: expected a positive number, got '0' (line 1)");
  EXPECT_EQ(message("nspg_seeds: 1.5"),
            "p.yaml: nspg_seeds: expected a whole number >= 0, got '1.5' (line 1)");
  EXPECT_EQ(message("base_height: low"),
            "p.yaml: base_height: expected a number or auto, got 'low' (line 1)");
  EXPECT_NE(message("environment_source: lidar").find("p.yaml: environment_source:"), std::string::npos)
      << message("environment_source: lidar");
  EXPECT_NE(message("sensor_depth_stride: 0").find("p.yaml: sensor_depth_stride:"), std::string::npos);
  EXPECT_NE(message("sensor_max_range: 0").find("p.yaml: sensor_max_range: expected a positive number"), std::string::npos);
  EXPECT_EQ(parse_params("environment_source: both", "p.yaml").environment_source, "both");
  EXPECT_TRUE(std::isnan(parse_params("base_height: auto", "p.yaml").base_height));
  EXPECT_DOUBLE_EQ(parse_params("base_height: 0.4", "p.yaml").base_height, 0.4);
  EXPECT_THROW((void)load_params("/nonexistent/planner.yaml"), PlannerError);
}
