// The simulated RGB-D camera: a 640 x 480 frame of the drill robot on its mobile base in a room
// (floor, three walls, a pillar), rendered headless (EGL surfaceless, Mesa llvmpipe), with and
// without the D400 noise; the noise alone, against a std::normal_distribution per value; and
// the cost of a renderer for a new model (a hot swap). Run: bench_render
// [--benchmark_filter=...]. Not a test: no timing assertion anywhere.
#include <benchmark/benchmark.h>
#include <mujoco/mujoco.h>

#include <algorithm>
#include <cmath>
#include <cstring>
#include <random>
#include <stdexcept>
#include <string>

#include "concert/cli/benchmark_main.hpp"
#include "concert/common/text.hpp"
#include "concert/sim/rgbd_renderer.hpp"
#include "concert/sim/sim_hardware.hpp"

namespace {

using concert::hardware::RgbdFrame;
using concert::sim::CameraParams;
using concert::sim::EglContext;
using concert::sim::RgbdRenderer;

concert::world::WorldShape box(const std::string& name, const Eigen::Vector3d& size,
                               const Eigen::Vector3d& position) {
  concert::world::WorldShape s;
  s.name = name;
  s.size = size;
  s.position = position;
  return s;
}

/// The robot in a room, through the simulator's own MJCF (with visual_mjcf for the camera).
struct Scene {
  Scene() {
    concert::world::World world;
    world.walls = {box("front", {0.2, 8.0, 3.0}, {3.0, 0.0, 1.5}),
                   box("left", {8.0, 0.2, 3.0}, {0.0, 3.0, 1.5}),
                   box("right", {8.0, 0.2, 3.0}, {0.0, -3.0, 1.5})};
    concert::world::WorldShape pillar = box("pillar", {0.3, 0.0, 3.0}, {1.8, -1.0, 1.5});
    pillar.type = concert::world::WorldShape::Type::kCylinder;
    world.obstacles = {pillar};
    const std::string mjcf = concert::sim::urdf_to_mjcf(
        concert::read_file(std::string(ROBOT_FIXTURES) + "/mobile_drill.urdf", "robot"), world,
        concert::sim::SimParams{});
    mjVFS vfs;
    mj_defaultVFS(&vfs);
    if (mj_makeEmptyFileVFS(&vfs, "scene.xml", static_cast<int>(mjcf.size())) != 0) {
      throw std::runtime_error("could not allocate the MuJoCo virtual file");
    }
    std::memcpy(vfs.filedata[0], mjcf.data(), mjcf.size());
    char error[1000] = "";
    m = mj_loadXML("scene.xml", &vfs, error, sizeof(error));
    mj_deleteVFS(&vfs);
    if (m == nullptr) {
      throw std::runtime_error(std::string("MuJoCo rejected the scene: ") + error);
    }
    d = mj_makeData(m);
    mj_forward(m, d);
    // Behind and above the robot, looking along +x at it and the front wall, 25 degrees down.
    const double tilt = 0.44;
    Eigen::Matrix3d r;
    r.col(2) = Eigen::Vector3d(std::cos(tilt), 0.0, -std::sin(tilt));  // optical z: forward, down
    r.col(0) = -Eigen::Vector3d::UnitY();                              // optical x: right
    r.col(1) = r.col(2).cross(r.col(0));                               // optical y: down
    camera.linear() = r;
    camera.translation() = Eigen::Vector3d(-1.6, 0.2, 1.4);
  }
  ~Scene() {
    mj_deleteData(d);
    mj_deleteModel(m);
  }
  Scene(const Scene&) = delete;
  Scene& operator=(const Scene&) = delete;
  mjModel* m{nullptr};
  mjData* d{nullptr};
  Eigen::Isometry3d camera{Eigen::Isometry3d::Identity()};
};

void BM_Render(benchmark::State& state) {
  const Scene scene;
  EglContext gl;
  CameraParams params;
  RgbdRenderer renderer(gl, scene.m, params);
  RgbdFrame frame;
  std::mt19937_64 rng(1);
  const bool noise = state.range(0) != 0;
  for (auto _ : state) {
    renderer.render(scene.d, scene.camera, frame);
    if (noise) {
      concert::sim::add_rgbd_noise(frame, params, rng);
    }
    benchmark::DoNotOptimize(frame.depth.data());
  }
}
BENCHMARK(BM_Render)->Arg(0)->Arg(1)->ArgName("noise")->Unit(benchmark::kMillisecond);

/// A rendered frame of the scene, to add noise to.
RgbdFrame rendered_frame() {
  const Scene scene;
  EglContext gl;
  RgbdRenderer renderer(gl, scene.m, CameraParams{});
  RgbdFrame frame;
  renderer.render(scene.d, scene.camera, frame);
  return frame;
}

void BM_Noise(benchmark::State& state) {
  const RgbdFrame clean = rendered_frame();
  RgbdFrame frame = clean;
  const CameraParams params;
  std::mt19937_64 rng(1);
  concert::sim::add_rgbd_noise(frame, params, rng);  // builds the table of normals once
  for (auto _ : state) {
    state.PauseTiming();
    frame.depth = clean.depth;
    frame.rgb = clean.rgb;
    state.ResumeTiming();
    concert::sim::add_rgbd_noise(frame, params, rng);
    benchmark::DoNotOptimize(frame.depth.data());
  }
}
BENCHMARK(BM_Noise)->Unit(benchmark::kMillisecond);

/// The same noise with a std::normal_distribution draw per value: what the table avoids.
void BM_NoiseNormalDistribution(benchmark::State& state) {
  const RgbdFrame clean = rendered_frame();
  RgbdFrame frame = clean;
  const CameraParams params;
  std::mt19937_64 rng(1);
  std::normal_distribution<float> normal(0.0f, 1.0f);
  const auto coefficient = static_cast<float>(
      params.depth_subpixel / (params.depth_focal * params.depth_baseline * 1000.0));
  for (auto _ : state) {
    state.PauseTiming();
    frame.depth = clean.depth;
    frame.rgb = clean.rgb;
    state.ResumeTiming();
    for (auto& z : frame.depth) {
      if (z != 0) {
        const auto zf = static_cast<float>(z);
        z = static_cast<std::uint16_t>(
            std::max(0.0f, std::nearbyint(zf + zf * zf * coefficient * normal(rng))));
      }
    }
    for (auto& c : frame.rgb) {
      c = static_cast<std::uint8_t>(
          std::clamp(std::nearbyint(static_cast<float>(c) + 2.0f * normal(rng)), 0.0f, 255.0f));
    }
    benchmark::DoNotOptimize(frame.depth.data());
  }
}
BENCHMARK(BM_NoiseNormalDistribution)->Unit(benchmark::kMillisecond);

/// A new renderer for a model (what a hot swap costs the camera thread).
void BM_MakeRenderer(benchmark::State& state) {
  const Scene scene;
  EglContext gl;
  for (auto _ : state) {
    RgbdRenderer renderer(gl, scene.m, CameraParams{});
    benchmark::DoNotOptimize(&renderer);
  }
}
BENCHMARK(BM_MakeRenderer)->Unit(benchmark::kMillisecond);

}  // namespace

int main(int argc, char** argv) {
  return concert::cli::benchmark_main(
      "bench_render",
      "The simulated RGB-D camera: a 640 x 480 frame rendered headless, with and without the D400 "
      "noise, and a new renderer (hot swap).",
      argc, argv);
}
