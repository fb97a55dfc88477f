#pragma once
// A camera anywhere in a world, no robot holding it: the simulator's own MJCF of the world
// (world_mjcf), its RGB-D renderer and its RealSense noise model, for tests and tools that need
// what a camera would see from a given pose (e.g. the drilling perception against the world's
// ground truth). Frames and pixels follow rgbd_renderer.hpp.

#include <Eigen/Geometry>
#include <memory>

#include "concert/hardware/sensors.hpp"
#include "concert/sim/sensor_params.hpp"
#include "concert/world/world.hpp"

namespace concert::sim {

/// Renders one world from free camera poses. Owns a headless OpenGL context (EglContext):
/// construct, use and destroy it on one thread.
class SceneCamera {
 public:
  /// Compiles the world (validate_world first: throws world::WorldError naming the field) and
  /// makes the renderer; throws hardware::HardwareError if there is no headless OpenGL.
  /// `params.noise` adds add_rgbd_noise() to every frame from a generator seeded with `seed`,
  /// so the n-th frame of two cameras built alike is the same.
  explicit SceneCamera(const world::World& world, const CameraParams& params = {},
                       unsigned seed = 1);
  ~SceneCamera();
  SceneCamera(const SceneCamera&) = delete;
  SceneCamera& operator=(const SceneCamera&) = delete;

  /// The world as the camera at `world_T_optical` sees it (optical frame: z along the axis, x
  /// right, y down). The frame's sensor is "scene_camera", its frame "scene_camera_optical",
  /// its stamp the number of frames rendered before it divided by params.rate [s].
  hardware::RgbdFrame render(const Eigen::Isometry3d& world_T_optical);

  [[nodiscard]] const hardware::CameraIntrinsics& intrinsics() const;

 private:
  struct Impl;
  std::unique_ptr<Impl> impl_;
};

/// The optical frame of a camera at `position` looking at `target`, level: its image x axis
/// horizontal (perpendicular to world z), image up towards world +z. Throws
/// std::invalid_argument if `target` is `position` or straight above or below it.
Eigen::Isometry3d look_at(const Eigen::Vector3d& position, const Eigen::Vector3d& target);

}  // namespace concert::sim
