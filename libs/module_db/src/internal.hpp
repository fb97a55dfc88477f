#pragma once
// Helpers shared by the two loaders (not installed).

#include <filesystem>
#include <string>
#include <vector>

#include "concert/module_db/module_description.hpp"

namespace concert::module_db::detail {

/// Throws ModuleDbError("<file name>: <field>: <what>").
[[noreturn]] void fail(const std::filesystem::path& file, const std::string& field, const std::string& what);

/// Checks the structure common to both formats (body/joint indices, one input, a tree of bodies,
/// finite numbers, non-negative masses, limits ordered) and normalises end-effectors (their
/// output connectors become TCP connectors). Throws ModuleDbError naming the file and field.
void validate_and_normalise(ModuleDescription& module, const std::filesystem::path& file);

/// Inverse of to_string(FrameKind) (only the YAML format names frame kinds); throws
/// std::invalid_argument for an unknown name.
FrameKind frame_kind_from_string(const std::string& name);

/// Attaches the sensors of a public sensor file (sensors/<prefix>_sensors.yaml) as sensor
/// frames to every module whose key starts with <prefix>, on the module's root body: lidars
/// (lidar3d), ultrasound sensors (sonar: x along the cone after then_rpy) and RGB-D cameras
/// (optical frames); other sensor types are skipped. Throws ModuleDbError naming the file and
/// field.
void attach_sensor_file(const std::filesystem::path& file, std::vector<ModuleDescription>& modules);

/// Joint limit magnitude from which a revolute joint counts as unbounded (continuous), rad.
inline constexpr double kUnboundedLimit = 1e6;

}  // namespace concert::module_db::detail
