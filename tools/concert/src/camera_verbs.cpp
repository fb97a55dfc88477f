#include "camera_verbs.hpp"

#include <algorithm>
#include <condition_variable>
#include <filesystem>
#include <iomanip>
#include <map>
#include <memory>
#include <mutex>
#include <opencv2/core.hpp>
#include <opencv2/imgcodecs.hpp>
#include <opencv2/imgproc.hpp>
#include <optional>
#include <sstream>

#include "concert/dds/endpoint.hpp"
#include "concert/idl_schema/cdr.hpp"
#include "concert/sensors_dds/conversions.hpp"

namespace concert::tool {
namespace {

namespace fs = std::filesystem;
using cli::Failure;

/// The cameras (RGB-D sensors) of a SensorList, in its order.
std::vector<msg::SensorDescription> cameras_of(const msg::SensorList& list) {
  std::vector<msg::SensorDescription> out;
  for (const auto& s : list.sensors()) {
    if (s.kind() == msg::SENSOR_RGBD) out.push_back(s);
  }
  return out;
}

std::string joined(const std::vector<std::string>& names) {
  if (names.empty()) return "none";
  std::string out;
  for (const auto& n : names) out += (out.empty() ? "" : ", ") + n;
  return out;
}

std::string seconds_text(double s) {
  std::ostringstream text;
  text << s;
  return text.str();
}

/// What the readers collected: the latest SensorList and, per camera, the latest colour
/// image, depth image and camera info.
class CameraListener {
 public:
  explicit CameraListener(dds::Participant& participant)
      : list_reader_(
            participant, dds::topics::sensor_list,
            [this](const msg::SensorList& l, const auto&) { keep([&] { sensor_list = l; }); }),
        rgb_reader_(
            participant, dds::topics::camera_rgb,
            [this](const msg::Image& i, const auto&) { keep([&] { rgb[i.sensor()] = i; }); }),
        depth_reader_(
            participant, dds::topics::camera_depth,
            [this](const msg::Image& i, const auto&) { keep([&] { depth[i.sensor()] = i; }); }),
        info_reader_(participant, dds::topics::camera_info,
                     [this](const msg::CameraInfo& i, const auto&) {
                       keep([&] { info[i.sensor()] = i; });
                     }) {}

  /// Calls f under the lock.
  template <class F>
  void with_lock(F&& f) {
    std::lock_guard lock(mutex_);
    f();
  }

  /// Waits until `done` (called under the lock) returns true or the deadline passes.
  template <class F>
  bool wait_until(std::chrono::steady_clock::time_point deadline, F&& done) {
    std::unique_lock lock(mutex_);
    return changed_.wait_until(lock, deadline, [&] { return done(); });
  }

  std::optional<msg::SensorList> sensor_list;
  std::map<std::string, std::optional<msg::Image>> rgb, depth;
  std::map<std::string, std::optional<msg::CameraInfo>> info;

 private:
  /// Stores a sample (f, under the lock) and wakes the waiters.
  template <class F>
  void keep(F&& f) {
    {
      std::lock_guard lock(mutex_);
      f();
    }
    changed_.notify_all();
  }

  std::mutex mutex_;
  std::condition_variable changed_;
  dds::Reader<msg::SensorList> list_reader_;
  dds::Reader<msg::Image> rgb_reader_;
  dds::Reader<msg::Image> depth_reader_;
  dds::Reader<msg::CameraInfo> info_reader_;
};

struct ListOptions {
  cli::DdsOptions dds;
};

int list(const ListOptions& o, std::ostream& out) {
  dds::Participant participant({.name = "concert_camera", .domain_id = o.dds.domain_id()});
  std::mutex mutex;
  std::condition_variable cv;
  std::optional<msg::SensorList> got;
  dds::Reader<msg::SensorList> reader(participant, dds::topics::sensor_list,
                                      [&](const msg::SensorList& l, const auto&) {
                                        {
                                          std::lock_guard lock(mutex);
                                          got = l;
                                        }
                                        cv.notify_all();
                                      });
  std::unique_lock lock(mutex);
  if (!cv.wait_for(lock, o.dds.timeout(), [&] { return got.has_value(); })) {
    throw Failure("no sensor list on " + std::string(dds::topics::sensor_list.name) + " within " +
                  seconds_text(o.dds.timeout_s) + " s (is the robot running on domain " +
                  std::to_string(participant.domain_id()) + "?)");
  }
  const auto cameras = cameras_of(*got);
  if (o.dds.json) {
    idl::Json rows = idl::Json::array();
    for (const auto& c : cameras)
      rows.push_back({{"name", c.name()}, {"frame", c.frame()}, {"rate", c.rate()}});
    out << idl::Json{{"model_version", got->model_version()}, {"cameras", rows}}.dump() << "\n";
    return 0;
  }
  out << cameras.size() << (cameras.size() == 1 ? " camera" : " cameras") << " at model version "
      << got->model_version() << "\n";
  for (const auto& c : cameras) {
    out << "  " << c.name() << "  frame " << c.frame() << "  " << c.rate() << " Hz\n";
  }
  return 0;
}

struct SnapshotOptions {
  cli::DdsOptions dds;
  std::string camera;
  std::string out_dir = ".";
};

/// A file name made of the camera name (anything but letters, digits, '_', '-', '.' becomes '_').
std::string file_stem(const std::string& camera) {
  std::string out = camera;
  for (char& c : out) {
    if (!std::isalnum(static_cast<unsigned char>(c)) && c != '_' && c != '-' && c != '.') c = '_';
  }
  return out;
}

int snapshot(const SnapshotOptions& o, std::ostream& out) {
  dds::Participant participant({.name = "concert_camera", .domain_id = o.dds.domain_id()});
  CameraListener l(participant);
  const auto deadline = std::chrono::steady_clock::now() + o.dds.timeout();

  std::string camera = o.camera;
  std::string unknown;  // set when the named camera is not among the robot's
  // A complete frame of `camera`: colour, depth and info with one stamp.
  auto complete = [&](const std::string& name) {
    const auto& rgb = l.rgb[name];
    const auto& depth = l.depth[name];
    const auto& info = l.info[name];
    return rgb && depth && info && rgb->stamp_ns() == depth->stamp_ns() &&
           rgb->stamp_ns() == info->stamp_ns();
  };
  auto known_cameras = [&] {
    std::vector<std::string> names;
    if (l.sensor_list) {
      for (const auto& c : cameras_of(*l.sensor_list)) names.push_back(c.name());
    }
    for (const auto& [name, image] : l.rgb) {
      if (image && std::find(names.begin(), names.end(), name) == names.end())
        names.push_back(name);
    }
    return names;
  };
  // The sensor list is latched but may reach a late joiner after the first frames: without
  // a camera named, frames alone decide only once this grace has passed.
  const auto list_grace =
      std::min(deadline, std::chrono::steady_clock::now() + std::chrono::seconds(2));
  const bool got = l.wait_until(deadline, [&] {
    const auto names = known_cameras();
    if (o.camera.empty()) {
      // Default: the robot's first camera; without a sensor list, the first that publishes.
      if (names.empty()) return false;
      if (!l.sensor_list && std::chrono::steady_clock::now() < list_grace) return false;
      camera = names.front();
    } else if (l.sensor_list && std::find(names.begin(), names.end(), camera) == names.end()) {
      unknown = joined(names);
      return true;
    }
    return complete(camera);
  });
  if (!unknown.empty()) {
    throw Failure("no camera '" + camera + "' on the robot; its cameras: " + unknown +
                  " (`concert camera list`)");
  }
  if (!got) {
    std::vector<std::string> names;
    l.with_lock([&] { names = known_cameras(); });
    const std::string within = " within " + seconds_text(o.dds.timeout_s) + " s";
    if (camera.empty()) {
      throw Failure("no camera publishes on " + std::string(dds::topics::camera_rgb.name) + within +
                    " (and no sensor list on " + std::string(dds::topics::sensor_list.name) +
                    "); is the robot running on domain " + std::to_string(participant.domain_id()) +
                    "?");
    }
    throw Failure("no complete frame of camera '" + camera + "' (" +
                  std::string(dds::topics::camera_rgb.name) + ", " +
                  std::string(dds::topics::camera_depth.name) + " and " +
                  std::string(dds::topics::camera_info.name) + " with one stamp)" + within +
                  "; cameras seen: " + joined(names));
  }

  msg::Image rgb, depth;
  msg::CameraInfo info;
  l.with_lock([&] {
    rgb = *l.rgb[camera];
    depth = *l.depth[camera];
    info = *l.info[camera];
  });
  const hardware::RgbdFrame frame = sensors_dds::to_rgbd_frame(rgb, depth, info);
  const int width = static_cast<int>(frame.intrinsics.width);
  const int height = static_cast<int>(frame.intrinsics.height);

  fs::create_directories(o.out_dir);
  const fs::path rgb_path = fs::path(o.out_dir) / (file_stem(camera) + "_rgb.png");
  const fs::path depth_path = fs::path(o.out_dir) / (file_stem(camera) + "_depth.png");
  cv::Mat bgr;
  cv::cvtColor(cv::Mat(height, width, CV_8UC3, const_cast<uint8_t*>(frame.rgb.data())), bgr,
               cv::COLOR_RGB2BGR);
  const cv::Mat depth_mat(height, width, CV_16UC1, const_cast<uint16_t*>(frame.depth.data()));
  if (!cv::imwrite(rgb_path.string(), bgr))
    throw Failure(rgb_path.string() + ": cannot write the PNG");
  if (!cv::imwrite(depth_path.string(), depth_mat))
    throw Failure(depth_path.string() + ": cannot write the PNG");

  // Depth seen: nearest and farthest valid pixel [m], and how many have no data.
  uint16_t nearest = 0, farthest = 0;
  size_t no_data = 0;
  for (uint16_t d : frame.depth) {
    if (d == 0) {
      ++no_data;
      continue;
    }
    nearest = nearest == 0 ? d : std::min(nearest, d);
    farthest = std::max(farthest, d);
  }
  const double scale = frame.depth_scale;
  if (o.dds.json) {
    out << idl::Json{{"camera", camera},
                     {"frame", frame.frame},
                     {"rgb", rgb_path.string()},
                     {"depth", depth_path.string()},
                     {"width", width},
                     {"height", height},
                     {"stamp_ns", rgb.stamp_ns()},
                     {"model_version", rgb.model_version()},
                     {"fx", frame.intrinsics.fx},
                     {"fy", frame.intrinsics.fy},
                     {"cx", frame.intrinsics.cx},
                     {"cy", frame.intrinsics.cy},
                     {"depth_scale", scale},
                     {"depth_min_seen", nearest * scale},
                     {"depth_max_seen", farthest * scale},
                     {"depth_no_data", no_data}}
               .dump()
        << "\n";
    return 0;
  }
  out << std::setprecision(6);
  out << "camera " << camera << " (frame " << frame.frame << ", model version "
      << rgb.model_version() << ")\n"
      << "  colour  " << rgb_path.string() << "\n"
      << "  depth   " << depth_path.string() << " (16-bit, " << scale * 1000.0 << " mm per unit)\n"
      << "  size    " << width << " x " << height << " px\n"
      << "  stamp   " << rgb.stamp_ns() << " ns (" << frame.stamp << " s)\n"
      << "  fx fy   " << frame.intrinsics.fx << " " << frame.intrinsics.fy << " px, cx cy "
      << frame.intrinsics.cx << " " << frame.intrinsics.cy << " px\n"
      << "  depth   " << nearest * scale << " .. " << farthest * scale << " m seen (camera range "
      << frame.depth_min << " .. " << frame.depth_max << " m), " << no_data << " px without data\n";
  return 0;
}

}  // namespace

void register_camera_verbs(cli::Cli& concert) {
  CLI::App& camera =
      concert.group(concert.app(), "camera", "the robot's cameras: list them, take a snapshot");

  auto lo = std::make_shared<ListOptions>();
  CLI::App& list_verb =
      concert.verb(camera, "list", "the cameras the robot has mounted (from its sensor list)",
                   [&concert, lo] { return list(*lo, concert.out()); });
  concert.add_dds_options(list_verb, lo->dds, 3.0, "how long to wait for the robot's sensor list");

  auto so = std::make_shared<SnapshotOptions>();
  CLI::App& snap =
      concert.verb(camera, "snapshot",
                   "wait for the next colour + depth frame of a camera and write <camera>_rgb.png "
                   "(8-bit RGB) and "
                   "<camera>_depth.png (16-bit, depth units of the camera, mm by default)",
                   [&concert, so] { return snapshot(*so, concert.out()); });
  snap.add_option("--camera", so->camera, "the camera (default: the robot's first)")
      ->type_name("NAME");
  snap.add_option("--out", so->out_dir, "folder the PNG files go to (made if missing)")
      ->type_name("DIR")
      ->default_str(".");
  concert.add_dds_options(snap, so->dds, 5.0, "how long to wait for a complete frame");
}

}  // namespace concert::tool
