#include "concert/dds/status_reporter.hpp"

#include <unistd.h>

#include <chrono>

namespace concert::dds {

std::string host_name() {
  char buf[256] = {};
  if (gethostname(buf, sizeof buf - 1) != 0 || buf[0] == '\0') return "unknown";
  return buf;
}

namespace {
int64_t now_ns() {
  return std::chrono::duration_cast<std::chrono::nanoseconds>(std::chrono::system_clock::now().time_since_epoch())
      .count();
}
}  // namespace

StatusReporter::StatusReporter(Participant& participant, std::string service, std::string host)
    : writer_(participant, topics::status) {
  status_.id(status_instance_id(service, host));
  status_.service(std::move(service));
  status_.host(std::move(host));
  status_.state(msg::SERVICE_STARTING);
  status_.model_version(0);
  status_.stamp_ns(now_ns());
  writer_.write(status_);
}

StatusReporter::~StatusReporter() {
  std::lock_guard lock(mutex_);
  status_.state(msg::SERVICE_STOPPED);
  status_.stamp_ns(now_ns());
  writer_.write(status_);
}

void StatusReporter::report(msg::ServiceState state, uint32_t model_version, const std::string& message) {
  std::lock_guard lock(mutex_);
  status_.state(state);
  status_.model_version(model_version);
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

}  // namespace concert::dds
