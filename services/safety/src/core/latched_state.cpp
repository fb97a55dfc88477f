#include "safety/latched_state.hpp"

#include <yaml-cpp/yaml.h>

#include <filesystem>
#include <fstream>
#include <stdexcept>

#include "concert/common/text.hpp"
#include "concert/config/config.hpp"
#include "safety/safety_monitor.hpp"

namespace concert::safety {

std::string to_yaml(const LatchedState& state) {
  YAML::Emitter out;
  out << YAML::Comment("concert_safety's latched state: rewritten on every change, read at start");
  out << YAML::BeginMap;
  out << YAML::Key << "mode" << YAML::Value
      << (state.mode == Mode::kStopped ? "STOPPED" : "RUNNING");
  out << YAML::Key << "causes" << YAML::Value << YAML::BeginSeq;
  for (const auto& c : state.causes) out << c;
  out << YAML::EndSeq;
  out << YAML::Key << "cause_keys" << YAML::Value << YAML::BeginSeq;
  for (const auto& k : state.cause_keys) out << k;
  out << YAML::EndSeq;
  out << YAML::Key << "engaged" << YAML::Value << YAML::Flow << YAML::BeginSeq;
  for (const auto e : state.engaged) out << std::string(to_string(e));
  out << YAML::EndSeq;
  out << YAML::Key << "watched" << YAML::Value << YAML::BeginMap;
  for (const auto& [who, incarnation] : state.watched) {
    out << YAML::Key << who << YAML::Value << YAML::DoubleQuoted << incarnation;
  }
  out << YAML::EndMap << YAML::EndMap;
  return std::string(out.c_str()) + "\n";
}

namespace {

LatchedState read_state(config::Document& doc) {
  LatchedState s;
  config::Map root = doc.root();
  std::string mode = "RUNNING";
  root.choice("mode", mode, {"RUNNING", "STOPPED"});
  s.mode = mode == "STOPPED" ? Mode::kStopped : Mode::kRunning;
  root.strings("causes", s.causes);
  root.strings("cause_keys", s.cause_keys);
  std::vector<std::string> engaged;
  root.strings("engaged", engaged);
  for (const auto& name : engaged) {
    bool known = false;
    for (std::size_t i = 0; i < kEStopSourceCount && !known; ++i) {
      const auto source = static_cast<EStopSource>(i);
      if (to_string(source) == name) {
        s.engaged.push_back(source);
        known = true;
      }
    }
    if (!known) root.fail("engaged", "unknown e-stop input '" + name + "'");
  }
  root.string_map("watched", s.watched);
  doc.finish();
  if (s.causes.size() != s.cause_keys.size()) {
    root.fail("cause_keys", "expected one per cause (" + std::to_string(s.causes.size()) +
                                " causes, " + std::to_string(s.cause_keys.size()) + " keys)");
  }
  if ((s.mode == Mode::kStopped) == s.causes.empty()) {
    root.fail("causes", s.mode == Mode::kStopped ? "a stop needs its causes"
                                                 : "RUNNING with causes");
  }
  // The service never writes RUNNING with an input engaged (engaging one stops the robot); a
  // file that says so was edited or damaged, and restoring it would run with an e-stop pressed.
  if (s.mode == Mode::kRunning && !s.engaged.empty()) {
    root.fail("engaged", "RUNNING with an e-stop input engaged");
  }
  for (const auto& [who, incarnation] : s.watched) {
    if (who.find('@') == std::string::npos) root.fail("watched", "'" + who + "' is not service@host");
  }
  return s;
}

}  // namespace

LatchedState parse_latched_state(const std::string& yaml, const std::string& origin) {
  // The service writes UTF-8 only; other bytes mean a damaged file, and yaml-cpp would pass them
  // through into names that the next write changes (a state that does not read back as itself).
  if (const auto at = invalid_utf8_at(yaml)) {
    throw config::ConfigError(origin + ": not valid UTF-8 (byte " + std::to_string(*at) + ")");
  }
  if (const auto at = yaml_control_character_at(yaml)) {
    throw config::ConfigError(origin + ": a control character YAML does not allow (byte " + std::to_string(*at) +
                              ")");
  }
  return config::Document::parse(yaml, origin).read_with(read_state);
}

LatchedState load_latched_state(const std::string& file) {
  return config::Document::load(file).read_with(read_state);
}

void save_latched_state(const std::string& file, const LatchedState& state) {
  const std::string tmp = file + ".tmp";
  {
    std::ofstream out(tmp, std::ios::trunc);
    out << to_yaml(state);
    if (!out.flush()) throw std::runtime_error("cannot write the safety state to " + tmp);
  }
  std::error_code ec;
  std::filesystem::rename(tmp, file, ec);
  if (ec) throw std::runtime_error("cannot rename " + tmp + " to " + file + ": " + ec.message());
}

}  // namespace concert::safety
