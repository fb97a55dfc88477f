#pragma once
// A deployable model bundle on disk: <dir>/robot.urdf, robot.srdf, controller.yaml and
// manifest.yaml (version, hash, tree version, modules, chains, end-effectors, files).

#include <filesystem>
#include <string>

#include "modelgen/model_generator.hpp"

namespace concert::modelgen {

/// Manifest YAML text of a model.
std::string write_manifest(const GeneratedModel& model);

/// Writes the bundle into `dir` (created if missing). Files are written to temporaries and
/// renamed, so a reader never sees a half-written bundle. Throws ModelError naming the file.
void write_bundle(const GeneratedModel& model, const std::filesystem::path& dir);

/// Version and hash stored in `dir`/manifest.yaml, or {0, ""} if there is none.
std::pair<uint64_t, std::string> read_bundle_version(const std::filesystem::path& dir);

}  // namespace concert::modelgen
