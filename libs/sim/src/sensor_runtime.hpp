#pragma once
// The simulated sensors at run time: what the control thread hands over each cycle (a
// snapshot of the MuJoCo state, copied into preallocated buffers), and the two sensor threads
// that turn it into data at the sensors' rates, in simulated time: one renders the RGB-D
// cameras (a headless OpenGL context is current on one thread only), one casts the rays of
// the lidars and sonars and reads the IMUs. Neither ever makes the control thread wait: a
// thread that falls behind skips samples.

#include <mujoco/mujoco.h>

#include <atomic>
#include <condition_variable>
#include <cstdint>
#include <memory>
#include <mutex>
#include <shared_mutex>
#include <string>
#include <thread>
#include <vector>

#include "concert/hardware/realtime_buffer.hpp"
#include "concert/hardware/sensors.hpp"
#include "concert/sim/sensor_params.hpp"

namespace concert::sim {

/// The MuJoCo state the sensors need, as of one control cycle.
struct SensorSnapshot {
  double time{-1.0};
  std::vector<double> qpos;
  std::vector<double> mocap_pos;
  std::vector<double> mocap_quat;
  std::vector<double> sensordata;
};

/// The sensors of one MuJoCo robot in one world: a private copy of the model (the control
/// thread writes drive gains into its own), the body each sensor sits on, and the hand-over
/// buffers from the control thread. Built off the control thread with the MuJoCo instance.
class SensorScene {
 public:
  /// Throws hardware::HardwareError naming a mount whose frame is not a link of the model.
  /// `root_link`: the robot's root link (the frame of the derived 2D scan).
  SensorScene(const mjModel* model, std::vector<SensorMount> mounts, const std::string& root_link,
              double floor_height);
  ~SensorScene();
  SensorScene(const SensorScene&) = delete;
  SensorScene& operator=(const SensorScene&) = delete;

  /// Control thread: hands the state of `data` over to both sensor threads (no allocation).
  void publish(const mjData* data);

  [[nodiscard]] const mjModel* model() const { return model_; }
  [[nodiscard]] const std::vector<SensorMount>& mounts() const { return mounts_; }
  /// MuJoCo body of mounts()[i].
  [[nodiscard]] int body(std::size_t i) const { return bodies_[i]; }
  /// sensordata addresses of the gyro and accelerometer of IMU mount i (-1 for other mounts).
  [[nodiscard]] int gyro_adr(std::size_t i) const { return gyro_adr_[i]; }
  [[nodiscard]] int accel_adr(std::size_t i) const { return accel_adr_[i]; }
  [[nodiscard]] double floor_height() const { return floor_height_; }
  /// The robot's root body (the frame of the derived 2D scan).
  [[nodiscard]] int root_body() const { return root_body_; }

  hardware::RealtimeBuffer<SensorSnapshot>& to_rays() { return to_rays_; }
  hardware::RealtimeBuffer<SensorSnapshot>& to_cameras() { return to_cameras_; }

 private:
  mjModel* model_{nullptr};
  std::vector<SensorMount> mounts_;
  std::vector<int> bodies_, gyro_adr_, accel_adr_;
  int root_body_{-1};
  double floor_height_{0.0};
  hardware::RealtimeBuffer<SensorSnapshot> to_rays_;
  hardware::RealtimeBuffer<SensorSnapshot> to_cameras_;
};

/// MuJoCo site name of an IMU mount (its gyro and accelerometer are named after it too).
std::string imu_site_name(const std::string& sensor);

/// The two sensor threads. They follow the scene the control thread runs (`active`), so a hot
/// swap makes the new tool's camera appear and the old one disappear.
class SensorRuntime {
 public:
  SensorRuntime(const SensorParams& params, const std::atomic<std::shared_ptr<SensorScene>>& active);
  ~SensorRuntime();
  SensorRuntime(const SensorRuntime&) = delete;
  SensorRuntime& operator=(const SensorRuntime&) = delete;

  /// Starts the threads on the first sink; nullptr stops delivering (the threads keep running
  /// idle until destruction).
  void set_sink(hardware::SensorSink* sink);

 private:
  void run_rays();
  void run_cameras();
  /// Waits up to `period` or until stopping; false when stopping.
  bool idle(std::chrono::microseconds period);
  /// Calls f(sink) if there is a sink; set_sink() waits for calls in flight.
  template <class F>
  void deliver(F&& f);

  SensorParams params_;
  const std::atomic<std::shared_ptr<SensorScene>>& active_;
  std::mutex mutex_;  // guards stopping_ and the threads' start
  std::condition_variable wake_;
  bool stopping_{false};
  std::shared_mutex sink_mutex_;
  hardware::SensorSink* sink_{nullptr};
  std::atomic<unsigned> sink_generation_{1};  // changes with each set_sink(): re-announce the sensors
  std::thread rays_, cameras_;
};

}  // namespace concert::sim
