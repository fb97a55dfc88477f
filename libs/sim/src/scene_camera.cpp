#include "concert/sim/scene_camera.hpp"

#include <mujoco/mujoco.h>

#include <cstring>
#include <random>
#include <stdexcept>
#include <string>

#include "concert/hardware/hardware.hpp"
#include "concert/sim/rgbd_renderer.hpp"
#include "world_mjcf.hpp"

namespace concert::sim {

namespace {

/// The world alone as a compiled MuJoCo model with its data after mj_forward.
struct WorldModel {
  WorldModel(const world::World& world, const CameraParams& params) {
    world::validate_world(world, "scene camera world");
    const WorldMjcf w = world_mjcf(world);
    // world_mjcf writes angles (a wall's yaw) in radians; MJCF's default is degrees.
    const std::string xml = "<mujoco model=\"scene\">\n<compiler angle=\"radian\"/>\n" +
                            visual_mjcf(params) + "<asset>\n" + w.assets +
                            "</asset>\n<worldbody>\n" + w.worldbody + "</worldbody>\n</mujoco>\n";
    mjVFS vfs;
    mj_defaultVFS(&vfs);
    if (mj_makeEmptyFileVFS(&vfs, "scene.xml", static_cast<int>(xml.size())) != 0) {
      throw hardware::HardwareError("scene camera: could not allocate the MuJoCo virtual file");
    }
    std::memcpy(vfs.filedata[0], xml.data(), xml.size());
    char error[1000] = "";
    m = mj_loadXML("scene.xml", &vfs, error, sizeof(error));
    mj_deleteVFS(&vfs);
    if (m == nullptr) {
      throw hardware::HardwareError(std::string("scene camera: MuJoCo rejected the world: ") +
                                    error);
    }
    fill_world_hfields(world, m);
    d = mj_makeData(m);
    mj_forward(m, d);
  }
  ~WorldModel() {
    if (d != nullptr) {
      mj_deleteData(d);
    }
    if (m != nullptr) {
      mj_deleteModel(m);
    }
  }
  WorldModel(const WorldModel&) = delete;
  WorldModel& operator=(const WorldModel&) = delete;
  mjModel* m{nullptr};
  mjData* d{nullptr};
};

}  // namespace

struct SceneCamera::Impl {
  Impl(const world::World& world, const CameraParams& camera, unsigned seed)
      : params(camera), model(world, camera), renderer(gl, model.m, camera), rng(seed) {}
  CameraParams params;
  EglContext gl;
  WorldModel model;
  RgbdRenderer renderer;  // after gl and model: destroyed before them
  std::mt19937_64 rng;
  long frames{0};
};

SceneCamera::SceneCamera(const world::World& world, const CameraParams& params, unsigned seed)
    : impl_(std::make_unique<Impl>(world, params, seed)) {}

SceneCamera::~SceneCamera() = default;

hardware::RgbdFrame SceneCamera::render(const Eigen::Isometry3d& world_T_optical) {
  hardware::RgbdFrame frame;
  impl_->renderer.render(impl_->model.d, world_T_optical, frame);
  add_rgbd_noise(frame, impl_->params, impl_->rng);
  frame.sensor = "scene_camera";
  frame.frame = "scene_camera_optical";
  frame.stamp = static_cast<double>(impl_->frames++) / impl_->params.rate;
  return frame;
}

const hardware::CameraIntrinsics& SceneCamera::intrinsics() const {
  return impl_->renderer.intrinsics();
}

Eigen::Isometry3d look_at(const Eigen::Vector3d& position, const Eigen::Vector3d& target) {
  const Eigen::Vector3d axis = target - position;
  const Eigen::Vector3d right = axis.cross(Eigen::Vector3d::UnitZ());
  if (axis.norm() < 1e-9 || right.norm() < 1e-9 * axis.norm()) {
    throw std::invalid_argument(
        "look_at: the target must differ from the position and not lie "
        "straight above or below it");
  }
  Eigen::Isometry3d t = Eigen::Isometry3d::Identity();
  t.linear().col(2) = axis.normalized();
  t.linear().col(0) = right.normalized();
  t.linear().col(1) = t.linear().col(2).cross(t.linear().col(0));
  t.translation() = position;
  return t;
}

}  // namespace concert::sim
