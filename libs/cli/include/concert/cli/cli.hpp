#pragma once
// The one command line of the stack, on CLI11: the `concert` tool's verbs (each service's CLI
// library registers its own) and the argv of every service executable.
//
//   cli::Cli concert("concert", "the CONCERT stack's command line", std::cout, std::cerr);
//   concert::discovery::register_verbs(concert);     // adds `concert discover`
//   return concert.run(argc, argv);
//
// Exit codes: 0 success (and --help), 1 failure while doing the work (not found, timed out, bad
// input file: any exception), 2 wrong command line (the message names the option).
// Common options of the verbs that talk DDS: --domain N, --timeout S (seconds), --json.

#include <CLI/CLI.hpp>
#include <chrono>
#include <cstdint>
#include <functional>
#include <map>
#include <optional>
#include <ostream>
#include <set>
#include <stdexcept>
#include <string>
#include <variant>
#include <vector>

namespace concert::cli {

/// A wrong command line found by the verb itself (e.g. a bad combination): exit code 2.
class UsageError : public std::runtime_error {
 public:
  using std::runtime_error::runtime_error;
};

/// A failure while doing the work: exit code 1 (as any other std::exception).
class Failure : public std::runtime_error {
 public:
  using std::runtime_error::runtime_error;
};

/// The options common to every verb that talks DDS, filled by the parser.
struct DdsOptions {
  std::optional<int32_t> domain;  ///< --domain N; unset: CONCERT_DOMAIN_ID, else 0
  double timeout_s = 0.0;  ///< --timeout S [s]; the verb's default, what it bounds is in its help
  bool json = false;       ///< --json: machine-readable output
  bool timeout_given = false;  ///< --timeout (or a deprecated spelling) was on the command line

  /// --domain, else CONCERT_DOMAIN_ID, else 0 (throws UsageError for a bad CONCERT_DOMAIN_ID).
  int32_t domain_id() const;
  /// timeout_s as a duration (0 stays 0: "no limit" where the verb says so).
  std::chrono::milliseconds timeout() const;
};

/// A number check with a clear message: "--count: 'x' is not a whole number >= 0".
/// `min`/`max` bound the value; `integer` requires a whole number; `min_open` excludes min.
CLI::Validator number(double min, double max = 1e300, bool integer = false, bool min_open = false);
/// Shorthands: any finite number, seconds (>= 0), positive seconds, whole numbers >= 0.
CLI::Validator real();
CLI::Validator seconds();
CLI::Validator positive_seconds();
CLI::Validator count();

/// A command line: the root program, its verbs and what each verb runs.
class Cli {
 public:
  Cli(std::string name, std::string description, std::ostream& out, std::ostream& err);
  Cli(const Cli&) = delete;
  Cli& operator=(const Cli&) = delete;

  CLI::App& app() { return app_; }
  std::ostream& out() { return out_; }
  std::ostream& err() { return err_; }

  /// A group of verbs (`concert topic ...`) under `parent`: it needs one of its verbs.
  CLI::App& group(CLI::App& parent, const std::string& name, const std::string& description);
  /// A verb under `parent` that runs `body` (its return value is the exit code).
  CLI::App& verb(CLI::App& parent, const std::string& name, const std::string& description,
                 std::function<int()> body);
  /// Runs `body` when `app` (the root, for a program without verbs) is the chosen command.
  void on_run(CLI::App& app, std::function<int()> body);

  /// Adds --domain N, --timeout S (default `timeout_s`, described by `timeout_help`) and --json
  /// to `verb`, stored in `options` (which must outlive this Cli), and marks the verb as one
  /// that talks DDS. Also accepts the deprecated `--timeout-ms MS` (hidden from the help).
  void add_dds_options(CLI::App& verb, DdsOptions& options, double timeout_s,
                       const std::string& timeout_help);
  /// Adds --domain N only (verbs that act on a domain without talking DDS themselves).
  static void add_domain_option(CLI::App& verb, std::optional<int32_t>& domain);
  /// Adds a seconds option `name` (e.g. "--wait") with a hidden deprecated milliseconds
  /// spelling `ms_name` (e.g. "--wait-ms"; "" for none), both stored in `seconds` [s];
  /// `given` (if not null) is set when either is on the command line.
  static CLI::Option* add_seconds_option(CLI::App& verb, const std::string& name,
                                         const std::string& ms_name, double& seconds,
                                         const std::string& help, bool* given = nullptr);

  /// Adds the hidden deprecated milliseconds spelling `ms_name` of the seconds option `instead`
  /// (which stores into `seconds`); `given` (if not null) is set when it is used.
  static CLI::Option* add_deprecated_ms_option(CLI::App& verb, const std::string& ms_name,
                                               double& seconds, CLI::Option* instead,
                                               bool* given = nullptr);
  /// Adds option `name` taking one of `choices` (shown as "a|b"), stored in `value`.
  static CLI::Option* add_choice(CLI::App& verb, const std::string& name, std::string& value,
                                 const std::vector<std::string>& choices, const std::string& help);
  /// True if `verb` was given the DDS options.
  bool talks_dds(const CLI::App& verb) const { return dds_verbs_.count(&verb) > 0; }
  /// Every verb (leaf of the tree) with its full name, e.g. "concert topic echo".
  std::vector<std::pair<std::string, CLI::App*>> verbs();

  /// Parses `args` (without the program name) and runs the chosen verb. Returns the exit code;
  /// errors are one line on err() naming the command and the option.
  int run(const std::vector<std::string>& args);
  int run(int argc, char** argv);
  /// Parses only (for tests of the command line itself): 0, or 2 with the message.
  int parse_only(const std::vector<std::string>& args);

 private:
  /// Parses; returns the chosen app, or the exit code when parsing ended the run.
  std::variant<CLI::App*, int> parse(const std::vector<std::string>& args);
  std::string path_of(const CLI::App* app) const;

  CLI::App app_;
  std::ostream& out_;
  std::ostream& err_;
  std::map<const CLI::App*, std::function<int()>> bodies_;
  std::set<const CLI::App*> dds_verbs_;
};

/// Runs `args` through a Cli named `name` with the given registrations (for tests of one
/// service's verbs and for small programs).
int run(const std::string& name, const std::vector<std::function<void(Cli&)>>& registrations,
        const std::vector<std::string>& args, std::ostream& out, std::ostream& err);

}  // namespace concert::cli
