#pragma once
// How a service executable is told to stop: SIGINT (Ctrl-C) and SIGTERM (the launcher,
// `docker stop`). Installed by main() before it starts spinning:
//
//   const std::atomic<bool>& stop = concert::cli::stop_on_signals();
//   node.spin(stop);  // returns once either signal arrived

#include <atomic>

namespace concert::cli {

/// Installs `handler` for SIGINT and SIGTERM. It runs as a signal handler: async-signal-safe
/// work only (e.g. a store into a lock-free atomic).
void on_stop_signals(void (*handler)(int));

/// Installs handlers for SIGINT and SIGTERM that set the returned flag (one flag for the whole
/// process, never reset), and returns it.
const std::atomic<bool>& stop_on_signals();

}  // namespace concert::cli
