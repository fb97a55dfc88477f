#include "concert/dds/status_reporter.hpp"

#include <unistd.h>

#include <cstdlib>

#include "concert/common/clock.hpp"
#include "concert/common/priority.hpp"

namespace concert::dds {

std::string host_name() {
  if (const char* env = std::getenv("CONCERT_HOST"); env != nullptr && *env != '\0') return env;
  char buf[256] = {};
  if (gethostname(buf, sizeof buf - 1) != 0 || buf[0] == '\0') return "unknown";
  return buf;
}

StatusReporter::StatusReporter(Participant& participant, std::string service, std::string host,
                               std::chrono::milliseconds heartbeat)
    : writer_(participant, topics::status), heartbeat_(heartbeat) {
  status_.id(status_instance_id(service, host));
  status_.service(std::move(service));
  status_.host(std::move(host));
  status_.state(msg::SERVICE_STARTING);
  status_.model_version(0);
  status_.stamp_ns(now_ns());
  writer_.write(status_);
  if (heartbeat_ > std::chrono::milliseconds::zero()) thread_ = std::thread([this] { beat(); });
}

StatusReporter::~StatusReporter() {
  {
    std::lock_guard lock(mutex_);
    stopping_ = true;
  }
  wake_.notify_all();
  if (thread_.joinable()) thread_.join();
  std::lock_guard lock(mutex_);
  status_.state(msg::SERVICE_STOPPED);
  status_.stamp_ns(now_ns());
  writer_.write(status_);
  // The writer goes away with us: give remote readers a moment to acknowledge the goodbye.
  writer_.get()->wait_for_acknowledgments(eprosima::fastrtps::Duration_t(0, 500'000'000));
}

void StatusReporter::beat() {
  // The heartbeat proves the process alive and on the network, not that its work keeps up. On
  // a loaded PC a heartbeat starved behind the service's own work (or a browser's) would read as
  // a dead service and stop the robot; this thread wakes five times a second for one write, so
  // it runs above the work when the process may raise it (else at the service's priority).
  (void)set_thread_nice(kHeartbeatNice);
  std::unique_lock lock(mutex_);
  auto next = std::chrono::steady_clock::now() + heartbeat_;
  while (!wake_.wait_until(lock, next, [this] { return stopping_; })) {
    status_.stamp_ns(now_ns());
    writer_.write(status_);
    next += heartbeat_;
    // After a long stall (suspended process), beat once and realign rather than burst.
    const auto now = std::chrono::steady_clock::now();
    if (next < now) next = now + heartbeat_;
  }
}

void StatusReporter::report(msg::ServiceState state, const ModelId& model,
                            const std::string& message) {
  std::lock_guard lock(mutex_);
  status_.state(state);
  status_.model_version(model.version);
  status_.model_hash(model.hash);
  status_.message(message);
  status_.stamp_ns(now_ns());
  writer_.write(status_);
}

void StatusReporter::report(msg::ServiceState state, uint32_t model_version,
                            const std::string& message) {
  std::lock_guard lock(mutex_);
  status_.state(state);
  if (status_.model_version() != model_version) status_.model_hash("");
  status_.model_version(model_version);
  status_.message(message);
  status_.stamp_ns(now_ns());
  writer_.write(status_);
}

void StatusReporter::refused(const std::string& message) {
  std::lock_guard lock(mutex_);
  status_.refusals(status_.refusals() + 1);
  status_.message(message);
  status_.stamp_ns(now_ns());
  writer_.write(status_);
}

void StatusReporter::note(const std::string& message) {
  std::lock_guard lock(mutex_);
  status_.message(message);
  status_.stamp_ns(now_ns());
  writer_.write(status_);
}

msg::ServiceState StatusReporter::state() const {
  std::lock_guard lock(mutex_);
  return status_.state();
}

uint32_t StatusReporter::model_version() const {
  std::lock_guard lock(mutex_);
  return status_.model_version();
}

ModelId StatusReporter::model() const {
  std::lock_guard lock(mutex_);
  return {status_.model_version(), status_.model_hash()};
}

uint32_t StatusReporter::refusals() const {
  std::lock_guard lock(mutex_);
  return status_.refusals();
}

}  // namespace concert::dds
