#include "dds/safety_node.hpp"


#include <filesystem>
#include <optional>
#include <sstream>
#include <thread>

#include "concert/common/clock.hpp"
#include "concert/model/dds/conversions.hpp"
#include "dds/conversions.hpp"

namespace concert::safety::dds {
namespace {

std::string summary(const SafetyStatus& status) {
  if (status.mode == Mode::kRunning) return "RUNNING";
  std::string text = "STOPPED";
  for (std::size_t i = 0; i < status.causes.size(); ++i)
    text += (i == 0 ? ": " : "; ") + status.causes[i];
  std::string engaged;
  for (const EStopSource e : status.engaged) engaged += (engaged.empty() ? "" : ", ") + std::string(to_string(e));
  text += engaged.empty() ? " (every e-stop input released)" : " (engaged: " + engaged + ")";
  return text;
}

}  // namespace

SafetyNode::SafetyNode(concert::dds::Participant& participant, Params params, std::ostream& log,
                       std::string state_file)
    // Restored before the readers below exist: a heartbeat taken in before the restore was
    // published and persisted as the fresh monitor's RUNNING, over the stop in the file,
    // which the restore then read back (the chaos test: a latched stop lost on a restart).
    : monitor_(restored_monitor(std::move(params), state_file, log)),
      log_(log),
      state_file_(std::move(state_file)),
      state_writer_(participant, concert::dds::topics::safety_state),
      status_(participant, "safety"),
      estops_(participant, concert::dds::topics::estop,
              [this](const auto& s, const auto&) { on_estop(s); }),
      statuses_(participant, concert::dds::topics::status,
                [this](const auto& s, const auto& info) {
                  // The status writer's GUID names the process: a new one is a restart.
                  std::ostringstream writer;
                  writer << info.sample_identity.writer_guid();
                  on_status(s, writer.str());
                }),
      models_(participant, concert::dds::topics::robot_model,
              [this](const auto& s, const auto&) { on_model(s); }),
      joint_states_(participant, concert::dds::topics::joint_state,
                    [this](const auto& s, const auto&) { on_joint_state(s); }),
      resets_(participant, concert::dds::topics::safety_reset,
              [this](const auto& s, const auto&) { on_reset(s); }) {
  // Reported under the lock, at the model the monitor holds: the model reader above may have
  // delivered the model already (a restarted safety joining a running system), and a "ready at
  // model 0" sent after on_model's report left a restarted safety looking model-less for good
  // (a chaos test run in CI: its limits of v2 loaded, its status at v0).
  std::lock_guard lock(mutex_);
  publish_locked(true);
  status_.report(msg::SERVICE_READY,
                 concert::dds::ModelId{monitor_.model_version(), model_hash_},
                 summary(monitor_.status()));
}

SafetyMonitor SafetyNode::restored_monitor(Params params, const std::string& state_file, std::ostream& log) {
  SafetyMonitor monitor(std::move(params), Clock::now());
  if (state_file.empty() || !std::filesystem::exists(state_file)) return monitor;
  try {
    const LatchedState state = load_latched_state(state_file);
    monitor.restore(state, Clock::now());
    log << "safety: restored from " << state_file << ": " << summary(monitor.status()) << "; watching "
        << state.watched.size() << " service instance(s) again" << std::endl;
  } catch (const std::exception& e) {
    // What it held is unknown: stopped until an operator looks.
    LatchedState unknown;
    unknown.mode = Mode::kStopped;
    unknown.causes = {std::string("safety: the latched state could not be read back: ") + e.what()};
    unknown.cause_keys = {"state"};
    monitor.restore(unknown, Clock::now());
    log << "safety: " << unknown.causes.front() << std::endl;
  }
  return monitor;
}

void SafetyNode::persist_locked() {
  if (state_file_.empty() || monitor_.latched_revision() == persisted_revision_) return;
  persisted_revision_ = monitor_.latched_revision();
  try {
    save_latched_state(state_file_, monitor_.latched());
  } catch (const std::exception& e) {
    log_ << "safety: " << e.what() << " (a restart would not find this state)" << std::endl;
  }
}

SafetyNode::~SafetyNode() = default;

std::optional<std::string> SafetyNode::publish_locked(bool force) {
  persist_locked();  // before the state goes out: a restart after this write keeps it
  const auto now = Clock::now();
  const bool changed = monitor_.revision() != published_revision_;
  if (!changed && !force && now - last_publish_ < monitor_.params().publish_period)
    return std::nullopt;
  state_writer_.write(to_msg(monitor_.status(), now_ns()));
  last_publish_ = now;
  if (!changed) return std::nullopt;
  published_revision_ = monitor_.revision();
  auto text = summary(monitor_.status());
  log_ << "safety: " << text << std::endl;
  return text;
}

void SafetyNode::note(const std::optional<std::string>& text) {
  if (text) status_.note(*text);
}

void SafetyNode::on_estop(const msg::EStopInput& input) {
  std::unique_lock lock(mutex_);
  auto source = to_core(input.source());
  if (!source) {
    // An input we cannot name is still an input: treat it as the software stop.
    log_ << "safety: e-stop input with unknown source " << static_cast<int>(input.source())
         << " treated as the software stop" << std::endl;
    source = EStopSource::kSoftware;
  }
  monitor_.set_estop(*source, input.engaged(), input.reason());
  const auto text = publish_locked(false);
  lock.unlock();
  note(text);
}

void SafetyNode::on_status(const msg::ServiceStatus& status, const std::string& incarnation) {
  std::unique_lock lock(mutex_);
  monitor_.on_heartbeat(status.service(), status.host(), status.state() == msg::SERVICE_STOPPED,
                        Clock::now(), incarnation);
  const auto text = publish_locked(false);
  lock.unlock();
  note(text);
}

void SafetyNode::on_model(const msg::RobotModel& message) {
  {
    // The same model again (a restarted modelgen republishes the running one): the limits and
    // the thermal load of every joint stay as they are.
    std::lock_guard lock(mutex_);
    if (monitor_.model_version() == message.version() && model_hash_ == message.content_hash()) {
      log_ << "safety: model v" << message.version() << " again with the same content: kept"
           << std::endl;
      return;
    }
  }
  // The limits table only: safety needs no URDF, so a model is not parsed whole here.
  std::optional<concert::model::LimitsTable> limits;
  std::string error;
  try {
    limits.emplace(concert::model::dds::to_description(message).joints, "model version " + std::to_string(message.version()));
  } catch (const concert::model::ModelError& e) {
    error = e.what();
  }
  {
    // The status is reported under the lock too, so that it always follows the latest model.
    std::lock_guard lock(mutex_);
    if (limits) {
      monitor_.set_model(message.version(), std::move(*limits));
      model_hash_ = message.content_hash();
      log_ << "safety: limits of model v" << message.version() << " (" << message.joints().size() << " joints)" << std::endl;
    } else {
      log_ << "safety: model v" << message.version() << " refused, limits of model v" << monitor_.model_version()
           << " kept: " << error << std::endl;
    }
    if (limits) {
      status_.report(msg::SERVICE_READY,
                     concert::dds::ModelId{message.version(), message.content_hash()},
                     summary(monitor_.status()));
    } else {
      const std::string refusal =
          "model v" + std::to_string(message.version()) + " refused: " + error;
      status_.report(msg::SERVICE_ERROR, monitor_.model_version(), refusal);
      status_.refused(refusal);
    }
  }
}

void SafetyNode::on_joint_state(const msg::JointState& state) {
  std::unique_lock lock(mutex_);
  if (monitor_.on_joint_state(to_core(state), Clock::now()) == SampleOutcome::kChecked) ++checked_samples_;
  const auto text = publish_locked(false);
  lock.unlock();
  note(text);
}

void SafetyNode::on_reset(const msg::SafetyReset& reset) {
  std::unique_lock lock(mutex_);
  // A reset written again by a client that had not heard the answer is the same press: taken
  // once, so that a copy arriving after a new stop cannot clear that stop.
  if (!resets_seen_.first_time(reset.request_id(), reset.stamp_ns())) {
    log_ << "safety: reset " << reset.request_id() << " by " << reset.source()
         << " seen again, ignored (taken once)" << std::endl;
    return;
  }
  const auto outcome =
      monitor_.reset(reset.source().empty() ? "unnamed" : reset.source(), Clock::now());
  log_ << "safety: " << outcome.message << std::endl;
  auto text = publish_locked(true);
  lock.unlock();
  note(outcome.accepted ? text : std::optional<std::string>(outcome.message));
}

void SafetyNode::tick() {
  std::unique_lock lock(mutex_);
  const uint64_t stalls = monitor_.own_stalls();
  monitor_.check_liveliness(Clock::now());
  if (monitor_.own_stalls() != stalls) {
    log_ << "safety: the liveliness check ran over " << monitor_.params().stall_checks
         << " periods late (this process was stalled); that time is not counted as silence"
         << std::endl;
  }
  const auto text = publish_locked(false);
  lock.unlock();
  note(text);
}

void SafetyNode::spin(const std::atomic<bool>& stop) {
  const auto period = monitor_.params().check_period;
  auto next = Clock::now();
  while (!stop) {
    tick();
    next += period;
    const auto now = Clock::now();
    if (next < now) next = now;
    std::this_thread::sleep_until(next);
  }
}

SafetyStatus SafetyNode::status() const {
  std::lock_guard lock(mutex_);
  return monitor_.status();
}

std::vector<std::string> SafetyNode::engaged_inputs() const {
  std::lock_guard lock(mutex_);
  return monitor_.engaged_inputs();
}

uint64_t SafetyNode::checked_samples() const {
  std::lock_guard lock(mutex_);
  return checked_samples_;
}

}  // namespace concert::safety::dds
