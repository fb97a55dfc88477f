#pragma once
// Small argument reader for the concert verbs: named options, flags and positionals, with
// errors that name the option and what was expected.

#include <optional>
#include <stdexcept>
#include <string>
#include <vector>

namespace concert::cli {

/// Wrong command line: printed with the verb and exit code 2.
class UsageError : public std::runtime_error {
 public:
  using std::runtime_error::runtime_error;
};

/// A failure while doing the work (not found, timed out, bad file): exit code 1.
class Failure : public std::runtime_error {
 public:
  using std::runtime_error::runtime_error;
};

class Args {
 public:
  explicit Args(std::vector<std::string> args) : args_(std::move(args)), used_(args_.size(), false) {}

  bool flag(const std::string& name) {
    for (size_t i = 0; i < args_.size(); ++i) {
      if (!used_[i] && args_[i] == name) {
        used_[i] = true;
        return true;
      }
    }
    return false;
  }

  std::optional<std::string> value(const std::string& name) {
    for (size_t i = 0; i < args_.size(); ++i) {
      if (used_[i]) continue;
      if (args_[i] == name) {
        if (i + 1 >= args_.size()) throw UsageError(name + " needs a value");
        used_[i] = used_[i + 1] = true;
        return args_[i + 1];
      }
      if (args_[i].rfind(name + "=", 0) == 0) {
        used_[i] = true;
        return args_[i].substr(name.size() + 1);
      }
    }
    return std::nullopt;
  }

  std::vector<std::string> values(const std::string& name) {
    std::vector<std::string> out;
    while (auto v = value(name)) out.push_back(*v);
    return out;
  }

  long integer(const std::string& name, long fallback, long min, long max) {
    const auto v = value(name);
    if (!v) return fallback;
    size_t end = 0;
    long n = 0;
    try {
      n = std::stol(*v, &end);
    } catch (const std::exception&) {
      end = 0;
    }
    if (end != v->size() || n < min || n > max) {
      throw UsageError(name + ": '" + *v + "' is not an integer from " + std::to_string(min) + " to " +
                       std::to_string(max));
    }
    return n;
  }

  /// The next unused argument that is not an option, or an error naming what it should be.
  std::string positional(const std::string& what) {
    for (size_t i = 0; i < args_.size(); ++i) {
      if (!used_[i] && args_[i].rfind("--", 0) != 0) {
        used_[i] = true;
        return args_[i];
      }
    }
    throw UsageError("missing " + what);
  }

  /// Throws for any argument nobody asked for.
  void finish() const {
    for (size_t i = 0; i < args_.size(); ++i) {
      if (!used_[i]) throw UsageError("unexpected argument '" + args_[i] + "'");
    }
  }

 private:
  std::vector<std::string> args_;
  std::vector<bool> used_;
};

}  // namespace concert::cli
