#pragma once
// Helpers of the system tests (tests/support/process.hpp waits on stdout only).

#include <chrono>
#include <string>
#include <thread>

#include "process.hpp"

namespace concert::system_test {

/// Waits (bounded) until the process' stderr contains `text`.
inline bool wait_for_err(const testing::Process& p, const std::string& text, std::chrono::milliseconds timeout) {
  const auto deadline = std::chrono::steady_clock::now() + timeout;
  while (p.err().find(text) == std::string::npos) {
    if (std::chrono::steady_clock::now() > deadline) return false;
    std::this_thread::sleep_for(std::chrono::milliseconds(50));
  }
  return true;
}

}  // namespace concert::system_test
