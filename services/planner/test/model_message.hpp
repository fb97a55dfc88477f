#pragma once
// Test helper: the RobotModel message modelgen would publish for an assembly, with a version.

#include <cstdint>
#include <filesystem>

#include "concert/model/dds/conversions.hpp"
#include "planner/fixtures.hpp"

namespace concert::planner::testing {

inline msg::RobotModel model_message(const std::filesystem::path& assembly, uint32_t version) {
  msg::RobotModel m = model::dds::to_msg(fixtures::generated_model(assembly).description(), 0);
  m.version(version);
  return m;
}

}  // namespace concert::planner::testing
