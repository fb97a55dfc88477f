#include "concert/sim/rgbd_renderer.hpp"

#include "concert/sim/geom_groups.hpp"

#include <EGL/egl.h>
#include <EGL/eglext.h>
#include <mujoco/mujoco.h>

#include <algorithm>
#include <cmath>
#include <mutex>
#include <sstream>
#include <vector>

#include "concert/hardware/hardware.hpp"

namespace concert::sim {

using hardware::CameraIntrinsics;
using hardware::HardwareError;
using hardware::RgbdFrame;

namespace {

std::string egl_error_name(EGLint code) {
  switch (code) {
    case EGL_SUCCESS:
      return "EGL_SUCCESS";
    case EGL_NOT_INITIALIZED:
      return "EGL_NOT_INITIALIZED";
    case EGL_BAD_ACCESS:
      return "EGL_BAD_ACCESS";
    case EGL_BAD_ALLOC:
      return "EGL_BAD_ALLOC";
    case EGL_BAD_ATTRIBUTE:
      return "EGL_BAD_ATTRIBUTE";
    case EGL_BAD_CONFIG:
      return "EGL_BAD_CONFIG";
    case EGL_BAD_CONTEXT:
      return "EGL_BAD_CONTEXT";
    case EGL_BAD_DISPLAY:
      return "EGL_BAD_DISPLAY";
    case EGL_BAD_MATCH:
      return "EGL_BAD_MATCH";
    case EGL_BAD_PARAMETER:
      return "EGL_BAD_PARAMETER";
    default: {
      std::ostringstream s;
      s << "EGL error 0x" << std::hex << code;
      return s.str();
    }
  }
}

[[noreturn]] void egl_fail(const std::string& step, const std::string& hint) {
  throw HardwareError("RGB-D renderer: " + step + " failed (" + egl_error_name(eglGetError()) +
                      "); " + hint);
}

// EGL displays are not reference counted: the process's surfaceless display is initialised by
// the first EglContext and terminated when the last one goes.
std::mutex display_mutex;
int display_users = 0;

constexpr std::size_t kNormalTableBits = 20;
constexpr std::size_t kNormalTableSize = std::size_t{1} << kNormalTableBits;

// 2^20 standard normals from a fixed seed, built once per process (thread-safe).
const std::vector<float>& normal_table() {
  static const std::vector<float> table = [] {
    std::mt19937_64 gen(0x0123456789abcdefULL);
    std::normal_distribution<float> normal(0.0f, 1.0f);
    std::vector<float> t(kNormalTableSize);
    for (auto& v : t) {
      v = normal(gen);
    }
    return t;
  }();
  return table;
}

}  // namespace

EglContext::EglContext() {
  const char* const mesa =
      "install libegl-mesa0 (Mesa's EGL) and libgl1-mesa-dri (its llvmpipe software renderer)";
  auto get_platform_display = reinterpret_cast<PFNEGLGETPLATFORMDISPLAYEXTPROC>(
      eglGetProcAddress("eglGetPlatformDisplayEXT"));
  if (get_platform_display == nullptr) {
    egl_fail("eglGetProcAddress(\"eglGetPlatformDisplayEXT\") (EGL_EXT_platform_base)",
             std::string("no EGL vendor library is installed: ") + mesa);
  }
  EGLDisplay display =
      get_platform_display(EGL_PLATFORM_SURFACELESS_MESA, EGL_DEFAULT_DISPLAY, nullptr);
  if (display == EGL_NO_DISPLAY) {
    egl_fail("eglGetPlatformDisplayEXT(EGL_PLATFORM_SURFACELESS_MESA)",
             std::string("Mesa's surfaceless platform is missing: ") + mesa);
  }
  {
    const std::lock_guard lock(display_mutex);
    EGLint major = 0;
    EGLint minor = 0;
    if (eglInitialize(display, &major, &minor) != EGL_TRUE) {
      egl_fail("eglInitialize (surfaceless display)", mesa);
    }
    ++display_users;
  }
  display_ = display;
  try {
    const EGLint config_attribs[] = {EGL_SURFACE_TYPE,
                                     EGL_PBUFFER_BIT,
                                     EGL_RED_SIZE,
                                     8,
                                     EGL_GREEN_SIZE,
                                     8,
                                     EGL_BLUE_SIZE,
                                     8,
                                     EGL_ALPHA_SIZE,
                                     8,
                                     EGL_DEPTH_SIZE,
                                     24,
                                     EGL_STENCIL_SIZE,
                                     8,
                                     EGL_RENDERABLE_TYPE,
                                     EGL_OPENGL_BIT,
                                     EGL_NONE};
    EGLConfig config = nullptr;
    EGLint configs = 0;
    if (eglChooseConfig(display, config_attribs, &config, 1, &configs) != EGL_TRUE || configs < 1) {
      egl_fail("eglChooseConfig (RGBA8, depth 24, stencil 8, desktop OpenGL)",
               std::string("no such configuration on the surfaceless display: ") + mesa);
    }
    // The default API is OpenGL ES; MuJoCo draws with desktop OpenGL.
    if (eglBindAPI(EGL_OPENGL_API) != EGL_TRUE) {
      egl_fail("eglBindAPI(EGL_OPENGL_API)",
               "the EGL implementation has no desktop OpenGL: " + std::string(mesa));
    }
    EGLContext context = eglCreateContext(display, config, EGL_NO_CONTEXT, nullptr);
    if (context == EGL_NO_CONTEXT) {
      egl_fail("eglCreateContext (desktop OpenGL)", mesa);
    }
    context_ = context;
    if (eglMakeCurrent(display, EGL_NO_SURFACE, EGL_NO_SURFACE, context) != EGL_TRUE) {
      egl_fail("eglMakeCurrent (no surface, EGL_KHR_surfaceless_context)", mesa);
    }
  } catch (...) {
    release();
    throw;
  }
}

EglContext::~EglContext() { release(); }

void EglContext::release() noexcept {
  if (display_ == nullptr) {
    return;
  }
  if (context_ != nullptr) {
    if (is_current()) {
      eglMakeCurrent(display_, EGL_NO_SURFACE, EGL_NO_SURFACE, EGL_NO_CONTEXT);
    }
    eglDestroyContext(display_, context_);
    context_ = nullptr;
  }
  const std::lock_guard lock(display_mutex);
  if (--display_users == 0) {
    eglTerminate(display_);
  }
  display_ = nullptr;
}

bool EglContext::is_current() const {
  return context_ != nullptr && eglGetCurrentContext() == context_;
}

void EglContext::make_current() {
  if (is_current()) {
    return;
  }
  if (eglMakeCurrent(display_, EGL_NO_SURFACE, EGL_NO_SURFACE, context_) != EGL_TRUE) {
    egl_fail("eglMakeCurrent",
             "an OpenGL context is current on one thread only: use a renderer on the thread "
             "that made its EglContext");
  }
}

CameraIntrinsics camera_intrinsics(const CameraParams& params) {
  CameraIntrinsics k;
  k.width = params.width;
  k.height = params.height;
  k.fx = params.focal;
  k.fy = params.focal;
  k.cx = (static_cast<double>(params.width) - 1.0) / 2.0;
  k.cy = (static_cast<double>(params.height) - 1.0) / 2.0;
  return k;
}

std::string visual_mjcf(const CameraParams& params) {
  // Lit colour = rgba * (ambient + diffuse * cos(incidence)): 0.4 + 0.6 facing the camera.
  // Shadow maps of 1024^2 for the model's own lights: MuJoCo's default 4096^2 makes every
  // render context cost ~100 ms on llvmpipe (~5 ms with this).
  return "<visual>\n<global offwidth=\"" + std::to_string(params.width) + "\" offheight=\"" +
         std::to_string(params.height) +
         "\"/>\n<quality offsamples=\"0\" shadowsize=\"1024\"/>\n"
         "<headlight ambient=\"0.4 0.4 0.4\" diffuse=\"0.6 0.6 0.6\" specular=\"0 0 "
         "0\"/>\n</visual>\n";
}

struct RgbdRenderer::Impl {
  Impl(EglContext& context, const mjModel* model, const CameraParams& camera_params)
      : gl(context),
        m(model),
        params(camera_params),
        intrinsics(camera_intrinsics(camera_params)) {}
  Impl(const Impl&) = delete;
  Impl& operator=(const Impl&) = delete;
  ~Impl() {
    if (context_made) {
      try {
        gl.make_current();
        mjr_freeContext(&con);
      } catch (const HardwareError&) {
        // The context is current on another thread: its GL objects go with the context.
      }
    }
    if (scene_made) {
      mjv_freeScene(&scene);
    }
  }
  EglContext& gl;
  const mjModel* m;
  CameraParams params;
  CameraIntrinsics intrinsics;
  float znear{0.0f};
  float zfar{0.0f};
  mjvScene scene{};
  mjrContext con{};
  mjvOption option{};
  mjvCamera camera{};
  mjvPerturb perturb{};
  bool scene_made{false};
  bool context_made{false};
  std::vector<unsigned char> rgb;  // as read: bottom row first
  std::vector<float> depth;        // window depth in [0, 1], bottom row first
};

RgbdRenderer::RgbdRenderer(EglContext& gl, const mjModel_* model, const CameraParams& params)
    : impl_(std::make_unique<Impl>(gl, model, params)) {
  Impl& r = *impl_;
  if (model == nullptr) {
    throw HardwareError("RGB-D renderer: no MuJoCo model");
  }
  if (params.width == 0 || params.height == 0 || !(params.focal > 0.0) ||
      !(params.depth_min > 0.0) || !(params.depth_max > params.depth_min) ||
      params.depth_max > 65.0) {
    throw HardwareError(
        "RGB-D renderer: camera parameters need width, height, focal > 0 and 0 < depth_min < "
        "depth_max "
        "<= 65 m (depth is 16-bit millimetres)");
  }
  if (model->vis.global.offwidth < static_cast<int>(params.width) ||
      model->vis.global.offheight < static_cast<int>(params.height)) {
    throw HardwareError("RGB-D renderer: the model's offscreen buffer is " +
                        std::to_string(model->vis.global.offwidth) + "x" +
                        std::to_string(model->vis.global.offheight) + ", the camera needs " +
                        std::to_string(params.width) + "x" + std::to_string(params.height) +
                        ": put visual_mjcf(camera params) into the model's MJCF");
  }
  gl.make_current();
  r.znear = static_cast<float>(params.depth_min / 2.0);
  r.zfar = static_cast<float>(std::max(2.0 * params.depth_max, 100.0));
  mjv_defaultOption(&r.option);
  r.option.geomgroup[kCameraHousingGeomGroup] = 0;  // cameras look past their housing
  std::fill(std::begin(r.option.sitegroup), std::end(r.option.sitegroup), mjtByte{0});
  mjv_defaultCamera(&r.camera);
  mjv_defaultPerturb(&r.perturb);
  mjv_defaultScene(&r.scene);
  mjv_makeScene(model, &r.scene, 2 * model->ngeom + 1000);
  r.scene_made = true;
  r.scene.flags[mjRND_HAZE] = 0;
  r.scene.flags[mjRND_REFLECTION] = 0;
  mjr_defaultContext(&r.con);
  mjr_makeContext(model, &r.con, mjFONTSCALE_50);
  r.context_made = true;
  mjr_setBuffer(mjFB_OFFSCREEN, &r.con);
  if (r.con.currentBuffer != mjFB_OFFSCREEN || r.con.offWidth < static_cast<int>(params.width) ||
      r.con.offHeight < static_cast<int>(params.height)) {
    throw HardwareError("RGB-D renderer: MuJoCo could not make a " + std::to_string(params.width) +
                        "x" + std::to_string(params.height) + " offscreen buffer (got " +
                        std::to_string(r.con.offWidth) + "x" + std::to_string(r.con.offHeight) +
                        ")");
  }
}

RgbdRenderer::~RgbdRenderer() = default;

const CameraIntrinsics& RgbdRenderer::intrinsics() const { return impl_->intrinsics; }
double RgbdRenderer::near_plane() const { return impl_->znear; }
double RgbdRenderer::far_plane() const { return impl_->zfar; }

void RgbdRenderer::render(const mjData_* data, const Eigen::Isometry3d& world_T_optical,
                          RgbdFrame& out) {
  Impl& r = *impl_;
  r.gl.make_current();
  const int w = static_cast<int>(r.intrinsics.width);
  const int h = static_cast<int>(r.intrinsics.height);
  const auto pixels = static_cast<std::size_t>(w) * static_cast<std::size_t>(h);
  r.rgb.resize(3 * pixels);
  r.depth.resize(pixels);
  out.rgb.resize(3 * pixels);
  out.depth.resize(pixels);

  // MuJoCo's API takes mjData non-const; mjv_updateScene only reads it.
  auto* d = const_cast<mjData*>(data);
  mjv_updateScene(r.m, d, &r.option, &r.perturb, &r.camera, mjCAT_STATIC | mjCAT_DYNAMIC, &r.scene);

  // The pinhole camera exactly: OpenGL's eye looks along -z with y up, i.e. forward = optical
  // z and up = -optical y. Window x in [0, w] (pixel edges) maps to the frustum's [left, right]
  // at the near plane; pixel u's centre is at window x = u + 0.5.
  const Eigen::Vector3d pos = world_T_optical.translation();
  const Eigen::Matrix3d rot = world_T_optical.rotation();
  const Eigen::Vector3d forward = rot.col(2);
  const Eigen::Vector3d up = -rot.col(1);
  const CameraIntrinsics& k = r.intrinsics;
  const double n = r.znear;
  const double top = n * (k.cy + 0.5) / k.fy;
  const double bottom = -n * (static_cast<double>(h) - k.cy - 0.5) / k.fy;
  const double left = -n * (k.cx + 0.5) / k.fx;
  const double right = n * (static_cast<double>(w) - k.cx - 0.5) / k.fx;
  for (auto& cam : r.scene.camera) {
    for (int i = 0; i < 3; ++i) {
      cam.pos[i] = static_cast<float>(pos[i]);
      cam.forward[i] = static_cast<float>(forward[i]);
      cam.up[i] = static_cast<float>(up[i]);
    }
    // MuJoCo's frustum is [center -+ halfwidth] with halfwidth = w / h * (top - bottom) / 2,
    // which is (right - left) / 2 because fx = fy.
    cam.frustum_center = static_cast<float>((left + right) / 2.0);
    cam.frustum_top = static_cast<float>(top);
    cam.frustum_bottom = static_cast<float>(bottom);
    cam.frustum_near = r.znear;
    cam.frustum_far = r.zfar;
  }
  // The headlight follows the camera: rebuild the lights from the camera just set.
  mjv_makeLights(r.m, d, &r.scene);

  mjr_setBuffer(mjFB_OFFSCREEN, &r.con);
  const mjrRect viewport{0, 0, w, h};
  mjr_render(viewport, &r.scene, &r.con);
  mjr_readPixels(r.rgb.data(), r.depth.data(), viewport, &r.con);

  // Rows come bottom-up. Metric z from window depth d of a perspective projection:
  // z = zn / (1 - d (1 - zn / zf)); d = 1 is the far plane (nothing there).
  const auto row_bytes = 3 * static_cast<std::size_t>(w);
  const double zn = r.znear;
  const double ratio = 1.0 - static_cast<double>(r.znear) / static_cast<double>(r.zfar);
  const double min_mm = r.params.depth_min * 1000.0;
  const double max_mm = r.params.depth_max * 1000.0;
  for (int row = 0; row < h; ++row) {
    const auto src = static_cast<std::size_t>(h - 1 - row);
    const auto dst = static_cast<std::size_t>(row);
    std::copy_n(r.rgb.data() + src * row_bytes, row_bytes, out.rgb.data() + dst * row_bytes);
    const float* depth_in = r.depth.data() + src * static_cast<std::size_t>(w);
    std::uint16_t* depth_out = out.depth.data() + dst * static_cast<std::size_t>(w);
    for (int col = 0; col < w; ++col) {
      const double window = depth_in[col];
      const double mm = 1000.0 * zn / (1.0 - window * ratio);
      depth_out[col] = window < 1.0 && mm >= min_mm && mm <= max_mm
                           ? static_cast<std::uint16_t>(std::lround(mm))
                           : 0;
    }
  }
  out.intrinsics = r.intrinsics;
  out.depth_scale = 0.001;
  out.depth_min = static_cast<float>(r.params.depth_min);
  out.depth_max = static_cast<float>(r.params.depth_max);
}

void add_rgbd_noise(RgbdFrame& frame, const CameraParams& params, std::mt19937_64& rng) {
  if (!params.noise) {
    return;
  }
  const std::vector<float>& normals = normal_table();
  const std::size_t w = frame.intrinsics.width;
  const std::size_t h = frame.intrinsics.height;
  if (frame.depth.size() != w * h || frame.rgb.size() != 3 * w * h) {
    throw HardwareError("add_rgbd_noise: frame of " + std::to_string(w) + "x" + std::to_string(h) +
                        " with " + std::to_string(frame.depth.size()) + " depth and " +
                        std::to_string(frame.rgb.size()) + " colour values");
  }
  const std::size_t row_values = 3 * w;
  if (row_values > kNormalTableSize / 2) {
    throw HardwareError("add_rgbd_noise: rows of " + std::to_string(w) + " pixels are too long");
  }
  // Each row reads a contiguous stretch of the table (no wrap-around: the loops vectorise);
  // rounding is +0.5 and truncation of values known to be positive.
  auto stretch = [&](std::size_t length) {
    return normals.data() + rng() % (kNormalTableSize - length);
  };
  // RMS [mm] = z[mm]^2 * subpixel / (focal * baseline[mm]).
  const auto coefficient = static_cast<float>(
      params.depth_subpixel / (params.depth_focal * params.depth_baseline * 1000.0));
  const auto min_mm = static_cast<float>(params.depth_min * 1000.0);
  const auto max_mm = static_cast<float>(params.depth_max * 1000.0);
  for (std::size_t row = 0; row < h; ++row) {
    const float* normal = stretch(w);
    std::uint16_t* depth = frame.depth.data() + row * w;
    for (std::size_t col = 0; col < w; ++col) {
      const auto z = static_cast<float>(depth[col]);
      const float noisy = z + z * z * coefficient * normal[col] + 0.5f;
      depth[col] = depth[col] != 0 && noisy >= min_mm && noisy < max_mm + 1.0f
                       ? static_cast<std::uint16_t>(noisy)
                       : std::uint16_t{0};
    }
  }
  const auto sigma = static_cast<float>(params.rgb_noise);
  if (!(sigma > 0.0f)) {
    return;
  }
  for (std::size_t row = 0; row < h; ++row) {
    const float* normal = stretch(row_values);
    std::uint8_t* rgb = frame.rgb.data() + row * row_values;
    for (std::size_t i = 0; i < row_values; ++i) {
      const float noisy = static_cast<float>(rgb[i]) + sigma * normal[i] + 0.5f;
      rgb[i] = static_cast<std::uint8_t>(std::clamp(noisy, 0.0f, 255.0f));
    }
  }
}

}  // namespace concert::sim
