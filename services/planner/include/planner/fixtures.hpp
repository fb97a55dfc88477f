#pragma once
// Models for tests and benchmarks, built in-process the way the running system builds them:
// assembly file -> simbus tree -> model generation (project module database) -> description.

#include <filesystem>
#include <string>

#include "concert/model_generation/model.hpp"
#include "planner/types.hpp"

namespace concert::planner::fixtures {

/// Folder of the planner's assemblies (morphology_a.yaml, morphology_b.yaml).
std::filesystem::path data_dir();
/// Model of an assembly file with the project's module database (data/module_db).
ModelDescription model_from_assembly(const std::filesystem::path& assembly, uint64_t version);
/// The model generated for an assembly (what modelgen would publish), for adapter tests.
model_generation::GeneratedModel generated_model(const std::filesystem::path& assembly);
/// A wall (normal -x, facing the robot at the origin) at x = `wall_x` and a drilling area on it
/// at height `z` [m] and lateral offset `y` [m]: frame z along the outward normal (-x).
Eigen::Isometry3d drilling_area(double wall_x, double y, double z);
/// A wall box 0.2 m thick, 6 m wide, 3.2 m high, front face at x = wall_x.
WorldBox wall_at(double wall_x);
/// Parameters seeded with `seed`, with budgets generous enough that a loaded machine (ctest -j2
/// next to a build) cannot make a plan fail: searches stop when they succeed, so the budget is
/// only a bound.
Params generous(uint64_t seed);

}  // namespace concert::planner::fixtures
