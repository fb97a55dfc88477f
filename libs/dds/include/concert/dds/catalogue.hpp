#pragma once
// THE topic catalogue: every topic of the system, its IDL type and its QoS class. Services,
// the concert tool and the tests all use it; nothing else names a topic. No DDS includes here,
// so Cyclone-based tests and DDS-free cores can read it too.

#include <cstdint>
#include <optional>
#include <span>
#include <string>
#include <string_view>

namespace concert::dds {

/// How a topic's endpoints are configured (QoS "in one place": see qos.hpp for Fast DDS).
enum class QosClass {
  /// Model-like state: RELIABLE, TRANSIENT_LOCAL, KEEP_LAST 1 (per instance). A late joiner
  /// gets the current value at once.
  kLatched,
  /// High-rate state stream: BEST_EFFORT, VOLATILE, KEEP_LAST 1. Never blocks the writer.
  kStream,
  /// Commands and requests: RELIABLE, VOLATILE, KEEP_LAST 8. Never blocks the writer.
  kCommand,
  /// Large samples (camera images, ~1 MB): a stream (BEST_EFFORT, VOLATILE, KEEP_LAST 1) whose
  /// writers publish asynchronously: write() hands the sample to a Fast DDS thread that sends
  /// its fragments, instead of sending them on the caller's (sensor) thread.
  kLargeStream,
};

struct QosSpec {
  bool reliable;
  bool transient_local;
  int32_t history_depth;      ///< KEEP_LAST depth
  bool asynchronous = false;  ///< writers publish from a Fast DDS thread (not on the wire)
};

/// The QoS a class stands for.
QosSpec qos_spec(QosClass qos);
std::string_view to_string(QosClass qos);

struct TopicInfo {
  std::string_view name;         ///< DDS topic name, e.g. "concert/ethercat/scan"
  std::string_view type_name;    ///< IDL type name as registered, e.g. "concert::msg::EscScan"
  QosClass qos;
  std::string_view description;  ///< one line: who writes it and what it carries
};

/// Every topic of the system.
std::span<const TopicInfo> catalogue();

/// The catalogue entry of a topic, if it is one of ours.
std::optional<TopicInfo> find_topic(std::string_view name);

/// DDS domain id from CONCERT_DOMAIN_ID (default 0). Throws std::invalid_argument naming the
/// variable and the value when it is not an integer in 0..232.
int32_t domain_id_from_env();

/// Parses a domain id given on a command line or in the environment; `what` names the source.
int32_t parse_domain_id(std::string_view text, std::string_view what);

/// RTPS puts domain d on the 250 UDP ports from 7400 + 250 d. Where those overlap the kernel's
/// ephemeral port range [low, high], any program's outgoing socket may take one of them, and a
/// Cyclone DDS participant of another domain whose transmit socket lands there joins this
/// domain (libs/dds/README.md). Returns the warning to print then, else "".
std::string domain_port_warning(int32_t domain_id, long low, long high);

/// Key of a ServiceStatus instance: FNV-1a 32-bit of "service@host" (keys stay < 16 bytes).
uint32_t status_instance_id(std::string_view service, std::string_view host);

/// Key of a sensor's instances on the sensor topics (Image, CameraInfo, LidarScan, Imu):
/// FNV-1a 32-bit of the sensor name, e.g. "camera_E". Writers and readers both use this.
uint32_t sensor_id(std::string_view sensor);

}  // namespace concert::dds
