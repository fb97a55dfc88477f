#include "concert/cli/stop_signals.hpp"

#include <csignal>

namespace concert::cli {
namespace {

std::atomic<bool> g_stop_requested{false};
static_assert(std::atomic<bool>::is_always_lock_free, "set from a signal handler");

void request_stop(int) { g_stop_requested = true; }

}  // namespace

void on_stop_signals(void (*handler)(int)) {
  std::signal(SIGINT, handler);
  std::signal(SIGTERM, handler);
}

const std::atomic<bool>& stop_on_signals() {
  on_stop_signals(request_stop);
  return g_stop_requested;
}

}  // namespace concert::cli
