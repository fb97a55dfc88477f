#pragma once
// The simulated RGB-D camera's renderer: MuJoCo draws the model offscreen in a headless OpenGL
// context (EGL surfaceless on Mesa's llvmpipe: no display, no GPU) as an ideal pinhole camera,
// and the colour and depth buffers become a hardware::RgbdFrame; add_rgbd_noise adds the
// noise of a RealSense D400.
//
// Conventions (hardware/sensors.hpp):
// * the camera pose is world_T_optical, the optical frame: z along the optical axis, x to the
//   right of the image, y down;
// * pixel (u, v) is column u, row v, row 0 at the top; the centre of pixel (u, v) is at
//   (u, v), so the image spans [-0.5, width - 0.5] x [-0.5, height - 0.5] and a point
//   (X, Y, Z) of the optical frame projects to u = fx X / Z + cx, v = fy Y / Z + cy, with
//   fx = fy = CameraParams::focal, cx = (width - 1) / 2, cy = (height - 1) / 2;
// * depth is z along the optical axis in millimetres (not the range along the ray); 0 = no
//   data: nothing there, or nearer than depth_min, or farther than depth_max.
//
// Threads: an OpenGL context is current on one thread. An EglContext and every RgbdRenderer
// made with it are constructed, used and destroyed on one thread (a camera thread), renderers
// before their context. Several renderers (cameras, or the models before and after a hot swap)
// share one context.

#include <Eigen/Geometry>
#include <cstdint>
#include <memory>
#include <random>
#include <string>

#include "concert/hardware/sensors.hpp"
#include "concert/sim/sensor_params.hpp"

struct mjModel_;
struct mjData_;

namespace concert::sim {

/// One headless OpenGL (compatibility profile) context: EGL on Mesa's surfaceless platform,
/// made current on the constructing thread. No DISPLAY, X server or GPU is needed.
/// Throws hardware::HardwareError naming the failing EGL step and the Debian package that
/// provides it (libegl-mesa0, libgl1-mesa-dri) when EGL or the software renderer is missing.
class EglContext {
 public:
  EglContext();
  ~EglContext();
  EglContext(const EglContext&) = delete;
  EglContext& operator=(const EglContext&) = delete;

  /// Whether this context is current on the calling thread.
  [[nodiscard]] bool is_current() const;
  /// Makes this context current on the calling thread (no-op if it is); throws
  /// hardware::HardwareError if it cannot be (e.g. it is current on another thread).
  void make_current();

 private:
  void release() noexcept;
  void* display_{nullptr};  // EGLDisplay
  void* context_{nullptr};  // EGLContext
};

/// The pinhole intrinsics of the camera `params` describes (see the conventions above):
/// fx = fy = focal, cx = (width - 1) / 2, cy = (height - 1) / 2.
hardware::CameraIntrinsics camera_intrinsics(const CameraParams& params);

/// The MJCF `<visual>` element a model needs for this camera: an offscreen buffer of at least
/// width x height (`<global offwidth offheight>`), no multisampling (`<quality offsamples="0">`:
/// 3x faster, same corner accuracy), 1024^2 shadow maps (`shadowsize`: MuJoCo's 4096^2 default
/// makes a renderer cost ~100 ms to build), and a headlight without specular highlights that shows
/// a grey (0.5) surface facing the camera as mid grey (128) and a white one as white (255).
std::string visual_mjcf(const CameraParams& params);

/// Renders RGB-D frames of one MuJoCo model. Construction makes MuJoCo's render context for
/// the model (uploads its meshes and textures: ~20 ms for the robot); a hot swap
/// builds a new renderer for the new model. Construct, use and destroy on the thread that owns
/// `gl`, before `gl` is destroyed; `model` must outlive the renderer.
class RgbdRenderer {
 public:
  /// Throws hardware::HardwareError if the model's offscreen buffer is smaller than the image
  /// (the model lacks visual_mjcf(params)) or `gl` cannot be made current here.
  RgbdRenderer(EglContext& gl, const mjModel_* model, const CameraParams& params);
  ~RgbdRenderer();
  RgbdRenderer(const RgbdRenderer&) = delete;
  RgbdRenderer& operator=(const RgbdRenderer&) = delete;

  /// The intrinsics every frame carries (camera_intrinsics(params)).
  [[nodiscard]] const hardware::CameraIntrinsics& intrinsics() const;
  /// [m] near clipping plane: half of depth_min. Nearer geometry is invisible (the camera's
  /// own housing); between it and depth_min the colour shows it and the depth reads 0.
  [[nodiscard]] double near_plane() const;
  /// [m] far clipping plane: the larger of 2 depth_max and 100 m, so the colour image shows
  /// what lies beyond depth_max (depth reads 0 there).
  [[nodiscard]] double far_plane() const;

  /// Renders the model in `data`'s state as the camera at `world_T_optical` sees it: fills
  /// out.rgb (top row first), out.depth [mm], out.intrinsics, out.depth_scale,
  /// out.depth_min and out.depth_max; leaves out.sensor, out.frame and out.stamp alone. Uses
  /// data's kinematics as they are (the caller ran mj_kinematics or mj_forward); `data` is not
  /// changed but must not be stepped by another thread meanwhile. No allocation after the
  /// first call with a given `out`.
  void render(const mjData_* data, const Eigen::Isometry3d& world_T_optical,
              hardware::RgbdFrame& out);

 private:
  struct Impl;
  std::unique_ptr<Impl> impl_;
};

/// Adds a RealSense D400's noise to a rendered frame (nothing if !params.noise):
/// * depth: on every valid pixel (depth != 0), zero-mean Gaussian with the RMS of Intel's
///   model, z^2 * depth_subpixel / (depth_focal * depth_baseline), rounded to millimetres; a
///   result outside [depth_min, depth_max] reads 0 (no data), as the camera invalidates it;
/// * colour: zero-mean Gaussian with std-dev rgb_noise per channel, rounded, clamped to 0..255.
/// The standard normals come from a fixed table of 2^20 values (generated once per process
/// from a fixed seed); each image row reads a contiguous stretch of it from an offset drawn
/// from `rng`. Consecutive values are independent, so pixels are; two rows may share a stretch
/// of the table (shifted), which no consumer of sensor noise can tell. At 640 x 480 this costs
/// ~2 ms of CPU per frame, ~17x less than a std::normal_distribution draw per value
/// (bench_render measures both). Deterministic for a given `rng` state.
void add_rgbd_noise(hardware::RgbdFrame& frame, const CameraParams& params, std::mt19937_64& rng);

}  // namespace concert::sim
