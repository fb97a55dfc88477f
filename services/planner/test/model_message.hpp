#pragma once
// Test helper: the RobotModel message modelgen publishes for an assembly, with a version.

#include <cstdint>
#include <filesystem>

#include "dds/conversions.hpp"  // modelgen's IDL conversions
#include "planner/fixtures.hpp"

namespace concert::planner::testing {

inline msg::RobotModel model_message(const std::filesystem::path& assembly, uint32_t version) {
  msg::RobotModel m = modelgen::dds::to_msg(fixtures::generated_model(assembly), 0);
  m.version(version);
  return m;
}

}  // namespace concert::planner::testing
