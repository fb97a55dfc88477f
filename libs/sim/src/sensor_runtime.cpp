#include "sensor_runtime.hpp"

#include <algorithm>
#include <cmath>
#include <iostream>
#include <optional>
#include <random>

#include "concert/hardware/hardware.hpp"
#include "concert/sim/imu_simulator.hpp"
#include "concert/sim/ray_sensors.hpp"
#include "concert/sim/rgbd_renderer.hpp"

namespace concert::sim {

using hardware::HardwareError;
using hardware::SensorType;

namespace {

/// FNV-1a 64: a stable per-sensor noise stream from the seed and the sensor's name.
std::uint64_t stream_seed(unsigned seed, const std::string& name) {
  std::uint64_t h = 1469598103934665603ULL ^ seed;
  for (const char c : name) {
    h = (h ^ static_cast<unsigned char>(c)) * 1099511628211ULL;
  }
  return h;
}

SensorSnapshot make_snapshot(const mjModel* m) {
  SensorSnapshot s;
  s.qpos.assign(static_cast<std::size_t>(m->nq), 0.0);
  s.mocap_pos.assign(static_cast<std::size_t>(3 * m->nmocap), 0.0);
  s.mocap_quat.assign(static_cast<std::size_t>(4 * m->nmocap), 0.0);
  s.sensordata.assign(static_cast<std::size_t>(m->nsensordata), 0.0);
  return s;
}

/// World pose of a MuJoCo body in `d` (kinematics computed).
Eigen::Isometry3d body_pose(const mjData* d, int body) {
  Eigen::Isometry3d pose = Eigen::Isometry3d::Identity();
  for (int r = 0; r < 3; ++r) {
    pose.translation()(r) = d->xpos[3 * body + r];
    for (int c = 0; c < 3; ++c) {
      pose.linear()(r, c) = d->xmat[9 * body + 3 * r + c];
    }
  }
  return pose;
}

/// Sets `d` to the snapshot's state and computes its kinematics.
void apply(const mjModel* m, mjData* d, const SensorSnapshot& s) {
  std::copy(s.qpos.begin(), s.qpos.end(), d->qpos);
  std::copy(s.mocap_pos.begin(), s.mocap_pos.end(), d->mocap_pos);
  std::copy(s.mocap_quat.begin(), s.mocap_quat.end(), d->mocap_quat);
  mj_kinematics(m, d);
  mj_camlight(m, d);
}

struct DataDeleter {
  void operator()(mjData* d) const { mj_deleteData(d); }
};
using DataPtr = std::unique_ptr<mjData, DataDeleter>;

/// Next due time of a periodic sensor, in simulated time: skips what was missed.
struct Schedule {
  double period{0.0};
  double next{0.0};
  bool due(double t) {
    if (period <= 0.0 || t + 1e-9 < next) {
      return false;
    }
    next += period;
    if (next <= t) {
      next = t + period;  // fell behind (or time jumped): skip what was missed
    }
    return true;
  }
};

}  // namespace

std::string imu_site_name(const std::string& sensor) { return "imu:" + sensor; }

SensorScene::SensorScene(const mjModel* model, std::vector<SensorMount> mounts, const std::string& root_link,
                         double floor_height)
    : model_(mj_copyModel(nullptr, model)),
      mounts_(std::move(mounts)),
      root_body_(mj_name2id(model, mjOBJ_BODY, root_link.c_str())),
      floor_height_(floor_height),
      to_rays_([&] { return make_snapshot(model); }),
      to_cameras_([&] { return make_snapshot(model); }) {
  if (model_ == nullptr) {
    throw HardwareError("sim sensors: could not copy the MuJoCo model");
  }
  if (root_body_ < 0) {
    mj_deleteModel(model_);
    throw HardwareError("sim sensors: the robot's root link '" + root_link + "' is not a MuJoCo body");
  }
  for (const SensorMount& mount : mounts_) {
    const int body = mj_name2id(model_, mjOBJ_BODY, mount.frame.c_str());
    if (body < 0) {
      mj_deleteModel(model_);
      throw HardwareError("sim sensors: sensor '" + mount.name + "' is mounted at '" + mount.frame +
                          "', which is not a link of the simulated robot");
    }
    bodies_.push_back(body);
    int gyro = -1;
    int accel = -1;
    if (mount.type == SensorType::kImu) {
      const std::string site = imu_site_name(mount.name);  // imu_mjcf() names its sensors so
      const int g = mj_name2id(model_, mjOBJ_SENSOR, (site + "_gyro").c_str());
      const int a = mj_name2id(model_, mjOBJ_SENSOR, (site + "_accel").c_str());
      if (g < 0 || a < 0) {
        mj_deleteModel(model_);
        throw HardwareError("sim sensors: IMU '" + mount.name + "' has no MuJoCo gyro/accelerometer");
      }
      gyro = model_->sensor_adr[g];
      accel = model_->sensor_adr[a];
    }
    gyro_adr_.push_back(gyro);
    accel_adr_.push_back(accel);
  }
}

SensorScene::~SensorScene() { mj_deleteModel(model_); }

void SensorScene::publish(const mjData* d) {
  for (auto* buffer : {&to_rays_, &to_cameras_}) {
    SensorSnapshot& s = buffer->back();
    s.time = d->time;
    std::copy_n(d->qpos, s.qpos.size(), s.qpos.begin());
    std::copy_n(d->mocap_pos, s.mocap_pos.size(), s.mocap_pos.begin());
    std::copy_n(d->mocap_quat, s.mocap_quat.size(), s.mocap_quat.begin());
    std::copy_n(d->sensordata, s.sensordata.size(), s.sensordata.begin());
    buffer->publish();
  }
}

SensorRuntime::SensorRuntime(const SensorParams& params, const std::atomic<std::shared_ptr<SensorScene>>& active)
    : params_(params), active_(active) {}

SensorRuntime::~SensorRuntime() {
  {
    std::lock_guard lock(mutex_);
    stopping_ = true;
  }
  wake_.notify_all();
  if (rays_.joinable()) {
    rays_.join();
  }
  if (cameras_.joinable()) {
    cameras_.join();
  }
}

void SensorRuntime::set_sink(hardware::SensorSink* sink) {
  {
    std::unique_lock lock(sink_mutex_);
    sink_ = sink;
  }
  sink_generation_.fetch_add(1);
  std::lock_guard lock(mutex_);
  if (sink != nullptr && !rays_.joinable() && !stopping_) {
    rays_ = std::thread([this] { run_rays(); });
    cameras_ = std::thread([this] { run_cameras(); });
  }
}

template <class F>
void SensorRuntime::deliver(F&& f) {
  std::shared_lock lock(sink_mutex_);
  if (sink_ != nullptr) {
    f(*sink_);
  }
}

bool SensorRuntime::idle(std::chrono::microseconds period) {
  std::unique_lock lock(mutex_);
  wake_.wait_for(lock, period, [this] { return stopping_; });
  return !stopping_;
}

void SensorRuntime::run_rays() {
  std::shared_ptr<SensorScene> scene;
  DataPtr data;
  std::vector<std::size_t> lidars, sonars, imus;
  std::vector<std::mt19937_64> rng;
  std::vector<ImuSimulator> imu_sims;
  std::vector<double> imu_last;
  Schedule lidar_due, sonar_due;
  std::vector<Schedule> imu_due;
  const LidarSimulator lidar(params_.lidar);
  const SonarSimulator sonar(params_.sonar);
  std::vector<hardware::LidarScan> scans;
  std::vector<PosedLidarScan> posed;
  hardware::LaserScan2d scan2d;
  hardware::SonarRanges ranges;
  hardware::ImuSample imu_sample;
  std::vector<hardware::SensorInfo> infos;
  unsigned announced = 0;  // sink generation the mounted sensors were announced to
  while (idle(std::chrono::microseconds(1000))) {
    std::shared_ptr<SensorScene> now = active_.load();
    if (!now) {
      continue;
    }
    if (now != scene) {
      scene = std::move(now);
      data.reset(mj_makeData(scene->model()));
      lidars.clear();
      sonars.clear();
      imus.clear();
      rng.clear();
      imu_sims.clear();
      imu_last.clear();
      imu_due.clear();
      infos.clear();
      announced = 0;
      for (std::size_t i = 0; i < scene->mounts().size(); ++i) {
        const SensorMount& m = scene->mounts()[i];
        rng.emplace_back(stream_seed(params_.seed, m.name));
        infos.push_back({m.name, m.type, m.frame, sensor_rate(params_, m.type)});
        switch (m.type) {
          case SensorType::kLidar:
            lidars.push_back(i);
            break;
          case SensorType::kSonar:
            sonars.push_back(i);
            break;
          case SensorType::kImu:
            imus.push_back(i);
            imu_sims.emplace_back(params_.imu, stream_seed(params_.seed, m.name));
            imu_last.push_back(-1.0);
            imu_due.push_back({1.0 / params_.imu.rate, 0.0});
            break;
          case SensorType::kRgbd:
            break;
        }
      }
      lidar_due = {1.0 / params_.lidar.rate, 0.0};
      sonar_due = {1.0 / params_.sonar.rate, 0.0};
      scans.assign(lidars.size(), {});
      posed.assign(lidars.size(), {});
      ranges.sonars.assign(sonars.size(), {});
    }
    if (const unsigned generation = sink_generation_.load(); generation != announced) {
      announced = generation;
      deliver([&](hardware::SensorSink& sink) { sink.on_sensors(infos); });
    }
    if (!scene->to_rays().update()) {
      continue;
    }
    const SensorSnapshot& snap = scene->to_rays().front();
    const double t = snap.time;
    const mjModel* m = scene->model();
    for (std::size_t k = 0; k < imus.size(); ++k) {
      if (!imu_due[k].due(t)) {
        continue;
      }
      const std::size_t i = imus[k];
      const double dt = imu_last[k] < 0.0 ? 1.0 / params_.imu.rate : t - imu_last[k];
      imu_last[k] = t;
      const double* g = snap.sensordata.data() + scene->gyro_adr(i);
      const double* a = snap.sensordata.data() + scene->accel_adr(i);
      imu_sims[k].sample(Eigen::Vector3d(g[0], g[1], g[2]), Eigen::Vector3d(a[0], a[1], a[2]), dt, imu_sample);
      imu_sample.sensor = scene->mounts()[i].name;
      imu_sample.frame = scene->mounts()[i].frame;
      imu_sample.stamp = t;
      deliver([&](hardware::SensorSink& sink) { sink.on_imu(imu_sample); });
    }
    const bool lidar_now = !lidars.empty() && lidar_due.due(t);
    const bool sonar_now = !sonars.empty() && sonar_due.due(t);
    if (!lidar_now && !sonar_now) {
      continue;
    }
    apply(m, data.get(), snap);
    if (sonar_now) {
      ranges.stamp = t;
      for (std::size_t k = 0; k < sonars.size(); ++k) {
        const std::size_t i = sonars[k];
        hardware::SonarRange& r = ranges.sonars[k];
        r.sensor = scene->mounts()[i].name;
        r.frame = scene->mounts()[i].frame;
        r.range = sonar.range(m, data.get(), body_pose(data.get(), scene->body(i)), rng[i]);
        r.range_min = static_cast<float>(params_.sonar.range_min);
        r.range_max = static_cast<float>(params_.sonar.range_max);
        r.field_of_view = static_cast<float>(params_.sonar.field_of_view);
      }
      deliver([&](hardware::SensorSink& sink) { sink.on_sonars(ranges); });
    }
    if (lidar_now) {
      const Eigen::Isometry3d world_T_base = body_pose(data.get(), scene->root_body());
      for (std::size_t k = 0; k < lidars.size(); ++k) {
        const std::size_t i = lidars[k];
        posed[k] = {&scans[k], body_pose(data.get(), scene->body(i))};
        lidar.scan(m, data.get(), posed[k].world_T_sensor, rng[i], scans[k]);
        scans[k].sensor = scene->mounts()[i].name;
        scans[k].frame = scene->mounts()[i].frame;
        scans[k].stamp = t;
        deliver([&](hardware::SensorSink& sink) { sink.on_lidar(scans[k]); });
      }
      derive_scan2d(params_.scan2d, posed, world_T_base, scene->floor_height(),
                    mj_id2name(m, mjOBJ_BODY, scene->root_body()), scan2d);
      deliver([&](hardware::SensorSink& sink) { sink.on_scan2d(scan2d); });
    }
  }
}

void SensorRuntime::run_cameras() {
  std::optional<EglContext> context;
  try {
    context.emplace();
  } catch (const std::exception& e) {
    std::cerr << "sim sensors: no camera images: " << e.what() << "\n";
    return;
  }
  std::shared_ptr<SensorScene> scene;
  DataPtr data;
  std::optional<RgbdRenderer> renderer;
  std::vector<std::size_t> cameras;
  std::vector<std::mt19937_64> rng;
  std::vector<hardware::RgbdFrame> frames;
  Schedule due;
  while (idle(std::chrono::microseconds(1000))) {
    std::shared_ptr<SensorScene> now = active_.load();
    if (!now) {
      continue;
    }
    if (now != scene) {
      scene = std::move(now);
      renderer.reset();
      cameras.clear();
      rng.clear();
      for (std::size_t i = 0; i < scene->mounts().size(); ++i) {
        if (scene->mounts()[i].type == SensorType::kRgbd) {
          cameras.push_back(i);
          rng.emplace_back(stream_seed(params_.seed, scene->mounts()[i].name));
        }
      }
      frames.resize(cameras.size());
      if (!cameras.empty()) {
        data.reset(mj_makeData(scene->model()));
        renderer.emplace(*context, scene->model(), params_.camera);
      }
      due = {1.0 / params_.camera.rate, 0.0};
    }
    if (cameras.empty() || !scene->to_cameras().update()) {
      continue;
    }
    const SensorSnapshot& snap = scene->to_cameras().front();
    if (!due.due(snap.time)) {
      continue;
    }
    apply(scene->model(), data.get(), snap);
    for (std::size_t k = 0; k < cameras.size(); ++k) {
      const std::size_t i = cameras[k];
      hardware::RgbdFrame& frame = frames[k];
      renderer->render(data.get(), body_pose(data.get(), scene->body(i)), frame);
      add_rgbd_noise(frame, params_.camera, rng[k]);
      frame.sensor = scene->mounts()[i].name;
      frame.frame = scene->mounts()[i].frame;
      frame.stamp = snap.time;
      deliver([&](hardware::SensorSink& sink) { sink.on_rgbd(frame); });
    }
  }
}

}  // namespace concert::sim
