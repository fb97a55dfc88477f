#pragma once
// The work of the `bag` verbs (bag_verbs.cpp registers them): recording and playing need DDS,
// info reads the file only.

#include <atomic>
#include <optional>
#include <ostream>
#include <string>
#include <vector>

#include "concert/bag/mcap.hpp"
#include "concert/cli/cli.hpp"
#include "concert/dds/catalogue.hpp"

namespace concert::tool::bag_verbs {

/// Set by SIGINT/SIGTERM while a bag verb runs.
std::atomic<bool>& interrupted();

/// What a recorded channel's metadata holds: "qos" (latched, stream, command, large_stream) and
/// "keyed" (true/false); the player reads them back for topics that are not in the catalogue.
inline constexpr const char* kQosKey = "qos";
inline constexpr const char* kKeyedKey = "keyed";
/// Schema encoding and message encoding of every channel (MCAP's well-known names).
inline constexpr const char* kSchemaEncoding = "omgidl";
inline constexpr const char* kMessageEncoding = "cdr";
/// Name of the Metadata record a recording closes with (domain, topics, samples dropped).
inline constexpr const char* kRecordingMetadata = "concert_recording";

std::string qos_name(dds::QosClass qos);
std::optional<dds::QosClass> parse_qos_name(const std::string& name);

/// "2024-05-01T12:00:00.123456789Z" for nanoseconds since the Unix epoch.
std::string utc_text(uint64_t ns);

struct RecordOptions {
  std::vector<std::string> topics;  ///< empty: every catalogue topic
  std::string output;
  std::string compression = "zstd";
  bool force = false;   ///< overwrite an existing file
  cli::DdsOptions dds;  ///< dds.timeout_s: stop after this long (0: until Ctrl-C)
};
int record(const RecordOptions& options, std::ostream& out, std::ostream& err);

struct PlayOptions {
  std::string file;
  double rate = 1.0;
  bool loop = false;
  std::vector<std::string> topics;  ///< empty: every recorded topic
  double wait_s = 1.0;              ///< wait for readers to match before the first message
  cli::DdsOptions dds;              ///< dds.timeout_s: stop after this long (0: at the end)
};
int play(const PlayOptions& options, std::ostream& out, std::ostream& err);

int info(const std::string& file, bool json, std::ostream& out, std::ostream& err);

}  // namespace concert::tool::bag_verbs
