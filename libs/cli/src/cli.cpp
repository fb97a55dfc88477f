#include "concert/cli/cli.hpp"

#include <charconv>
#include <cmath>
#include <sstream>

#include "concert/common/text.hpp"
#include "concert/dds/catalogue.hpp"

namespace concert::cli {

int32_t DdsOptions::domain_id() const {
  if (domain) return *domain;
  try {
    return dds::domain_id_from_env();
  } catch (const std::invalid_argument& e) {
    throw UsageError(e.what());
  }
}

std::chrono::milliseconds DdsOptions::timeout() const {
  return std::chrono::milliseconds(std::llround(timeout_s * 1000.0));
}

namespace {

std::string text_of(double v) {
  std::ostringstream s;
  s << v;
  return s.str();
}

}  // namespace

CLI::Validator number(double min, double max, bool integer, bool min_open) {
  std::string what = integer ? "a whole number" : "a number";
  if (min <= -1e300 && max >= 1e300) {
    // any finite number
  } else if (max >= 1e300) {
    what += (min_open ? " > " : " >= ") + text_of(min);
  } else {
    what += " from " + text_of(min) + " to " + text_of(max);
  }
  return CLI::Validator(
      [=](std::string& text) -> std::string {
        double v = 0.0;
        bool ok = false;
        const char* end = text.data() + text.size();
        if (integer) {
          long long n = 0;
          const auto r = std::from_chars(text.data(), end, n);
          ok = r.ec == std::errc() && r.ptr == end;
          v = static_cast<double>(n);
        } else {
          const auto r = std::from_chars(text.data(), end, v);
          ok = r.ec == std::errc() && r.ptr == end && std::isfinite(v);
        }
        ok = ok && (min_open ? v > min : v >= min) && v <= max;
        return ok ? std::string() : "'" + text + "' is not " + what;
      },
      "", "number");
}

CLI::Validator real() { return number(-1e300); }
CLI::Validator seconds() { return number(0.0); }
CLI::Validator positive_seconds() { return number(0.0, 1e300, false, true); }
CLI::Validator count() { return number(0.0, 1e300, true); }

Cli::Cli(std::string name, std::string description, std::ostream& out, std::ostream& err)
    : app_(std::move(description), std::move(name)), out_(out), err_(err) {
  app_.get_formatter()->column_width(34);
}

CLI::App& Cli::group(CLI::App& parent, const std::string& name, const std::string& description) {
  if (&parent == &app_) app_.require_subcommand(1);
  CLI::App* sub = parent.add_subcommand(name, description);
  sub->require_subcommand(1);
  return *sub;
}

CLI::App& Cli::verb(CLI::App& parent, const std::string& name, const std::string& description,
                    std::function<int()> body) {
  if (&parent == &app_) app_.require_subcommand(1);
  CLI::App* sub = parent.add_subcommand(name, description);
  on_run(*sub, std::move(body));
  return *sub;
}

void Cli::on_run(CLI::App& app, std::function<int()> body) { bodies_[&app] = std::move(body); }

void Cli::add_domain_option(CLI::App& verb, std::optional<int32_t>& domain) {
  // The catalogue's rule and message for domain ids, as for CONCERT_DOMAIN_ID.
  const CLI::Validator domain_id(
      [](std::string& text) -> std::string {
        try {
          (void)dds::parse_domain_id(text, "");
          return "";
        } catch (const std::invalid_argument& e) {
          const std::string what = e.what();
          return what.substr(what.find('\'') == std::string::npos ? 0 : what.find('\''));
        }
      },
      "", "domain id");
  verb.add_option_function<int32_t>(
          "--domain", [&domain](const int32_t& id) { domain = id; },
          "DDS domain id (default: CONCERT_DOMAIN_ID, else 0)")
      ->type_name("N")
      ->check(domain_id);
}

CLI::Option* Cli::add_seconds_option(CLI::App& verb, const std::string& name,
                                     const std::string& ms_name, double& seconds,
                                     const std::string& help, bool* given) {
  CLI::Option* s = verb.add_option_function<double>(
                           name,
                           [&seconds, given](const double& v) {
                             seconds = v;
                             if (given != nullptr) *given = true;
                           },
                           help)
                       ->type_name("S")
                       ->check(cli::seconds())
                       ->default_str(text_of(seconds));
  if (!ms_name.empty()) add_deprecated_ms_option(verb, ms_name, seconds, s, given);
  return s;
}

CLI::Option* Cli::add_deprecated_ms_option(CLI::App& verb, const std::string& ms_name,
                                           double& seconds, CLI::Option* instead, bool* given) {
  CLI::Option* ms = verb.add_option_function<double>(
                            ms_name,
                            [&seconds, given](const double& v) {
                              seconds = v / 1000.0;
                              if (given != nullptr) *given = true;
                            },
                            "deprecated: " + instead->get_name() + " in seconds")
                        ->check(cli::seconds())
                        ->group("");
  return ms;
}

CLI::Option* Cli::add_choice(CLI::App& verb, const std::string& name, std::string& value,
                             const std::vector<std::string>& choices, const std::string& help) {
  CLI::Validator member = CLI::IsMember(choices);
  member.description("");  // the type name lists the choices already
  return verb.add_option(name, value, help)->type_name(join(choices, "|"))->check(member);
}

void Cli::add_dds_options(CLI::App& verb, DdsOptions& options, double timeout_s,
                          const std::string& timeout_help) {
  add_domain_option(verb, options.domain);
  options.timeout_s = timeout_s;
  add_seconds_option(verb, "--timeout", "--timeout-ms", options.timeout_s, timeout_help,
                     &options.timeout_given);
  verb.add_flag("--json", options.json, "machine-readable output (JSON)");
  dds_verbs_.insert(&verb);
}

std::string Cli::path_of(const CLI::App* app) const {
  std::vector<std::string> names;
  for (const CLI::App* a = app; a != nullptr; a = a->get_parent()) names.push_back(a->get_name());
  return join(std::vector<std::string>(names.rbegin(), names.rend()), " ");
}

std::vector<std::pair<std::string, CLI::App*>> Cli::verbs() {
  std::vector<std::pair<std::string, CLI::App*>> out;
  std::function<void(CLI::App&)> walk = [&](CLI::App& app) {
    const auto subs = app.get_subcommands([](CLI::App*) { return true; });
    if (subs.empty() || bodies_.count(&app)) out.emplace_back(path_of(&app), &app);
    for (CLI::App* sub : subs) walk(*sub);
  };
  walk(app_);
  return out;
}

namespace {

/// The deepest command chosen on the command line so far.
CLI::App* deepest(CLI::App& root) {
  CLI::App* app = &root;
  for (auto subs = app->get_subcommands(); !subs.empty(); subs = app->get_subcommands()) {
    app = subs.front();
  }
  return app;
}

std::string verb_names(CLI::App& app) {
  std::vector<std::string> names;
  for (const CLI::App* sub : app.get_subcommands([](CLI::App*) { return true; })) {
    names.push_back(sub->get_name());
  }
  return join(names);
}

}  // namespace

std::variant<CLI::App*, int> Cli::parse(const std::vector<std::string>& args) {
  std::vector<std::string> reversed(args.rbegin(), args.rend());  // CLI11 takes them backwards
  try {
    app_.parse(reversed);
  } catch (const CLI::CallForHelp&) {
    out_ << app_.help();
    return 0;
  } catch (const CLI::CallForAllHelp&) {
    out_ << app_.help("", CLI::AppFormatMode::All);
    return 0;
  } catch (const CLI::ParseError& e) {
    CLI::App* at = deepest(app_);
    const std::string path = path_of(at);
    std::string message = e.what();
    if (dynamic_cast<const CLI::RequiredError*>(&e) != nullptr &&
        message == "A subcommand is required") {
      const auto rest = at->remaining();
      message = (!rest.empty() && rest.front().rfind('-', 0) != 0)
                    ? "unknown verb '" + rest.front() + "' (one of: " + verb_names(*at) + ")"
                    : "missing verb (one of: " + verb_names(*at) + ")";
    }
    if (args.empty()) out_ << app_.help();
    err_ << path << ": " << message << " (see `" << path << " --help`)\n";
    return 2;
  }
  return deepest(app_);
}

int Cli::parse_only(const std::vector<std::string>& args) {
  const auto parsed = parse(args);
  if (const int* code = std::get_if<int>(&parsed)) return *code;
  return 0;
}

int Cli::run(const std::vector<std::string>& args) {
  const auto parsed = parse(args);
  if (const int* code = std::get_if<int>(&parsed)) return *code;
  CLI::App* chosen = std::get<CLI::App*>(parsed);
  const std::string path = path_of(chosen);
  const auto body = bodies_.find(chosen);
  if (body == bodies_.end()) {
    err_ << path << ": missing verb (one of: " << verb_names(*chosen) << ")\n";
    return 2;
  }
  try {
    return body->second();
  } catch (const UsageError& e) {
    err_ << path << ": " << e.what() << " (see `" << path << " --help`)\n";
    return 2;
  } catch (const std::exception& e) {
    err_ << path << ": " << e.what() << "\n";
    return 1;
  }
}

int Cli::run(int argc, char** argv) { return run(std::vector<std::string>(argv + 1, argv + argc)); }

int run(const std::string& name, const std::vector<std::function<void(Cli&)>>& registrations,
        const std::vector<std::string>& args, std::ostream& out, std::ostream& err) {
  Cli cli(name, "", out, err);
  for (const auto& r : registrations) r(cli);
  return cli.run(args);
}

}  // namespace concert::cli
