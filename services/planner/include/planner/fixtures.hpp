#pragma once
// Models for tests and benchmarks, built in-process the way the running system builds them:
// assembly file -> simbus tree -> model generation (project module database) -> description.

#include <cstdint>
#include <filesystem>
#include <random>
#include <string>

#include "concert/hardware/sensors.hpp"
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
/// A VLP-16-like lidar revolution (16 rings over +-15 deg, `columns` azimuths from -pi) taken
/// from `map_T_sensor` of a wall whose face is at x = `wall_x` (normal -x, 6 m wide about y = 0,
/// 3 m high on the floor) and of the floor z = 0, with Gaussian range noise of std-dev `sigma`
/// [m] drawn from `rng`. Beams that meet neither read 0 (no return). Sensor and frame names are
/// left to the caller.
hardware::LidarScan wall_scan(const Eigen::Isometry3d& map_T_sensor, double wall_x, double sigma, std::mt19937& rng,
                              std::uint32_t columns = 900);
/// Unit direction of beam (ring, column) of `scan` in its sensor frame.
Eigen::Vector3d beam(const hardware::LidarScan& scan, std::size_t ring, std::uint32_t column);
/// Parameters seeded with `seed`, with budgets generous enough that a loaded machine (ctest -j2
/// next to a build) cannot make a plan fail: searches stop when they succeed, so the budget is
/// only a bound.
Params generous(uint64_t seed);

}  // namespace concert::planner::fixtures
