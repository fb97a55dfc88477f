#include "verbs.hpp"

#include <memory>

#include "bag_verbs.hpp"
#include "bim_verbs.hpp"
#include "camera_verbs.hpp"
#include "concert/security/cli.hpp"
#include "launcher.hpp"
#include "scan_verbs.hpp"
#include "status_verbs.hpp"
#include "topic_verbs.hpp"

namespace concert::tool {
namespace {

constexpr const char* kFooter = R"(Common options of the verbs that talk DDS:
  --domain N     DDS domain id (default: CONCERT_DOMAIN_ID, else 0)
  --timeout S    seconds; what it bounds is in the verb's help
  --json         machine-readable output
`concert VERB --help` (or `concert help VERB...`) shows a verb's arguments.
Exit codes: 0 success, 1 failure (not found, timed out, bad input file), 2 wrong command line.)";

/// `concert help [VERB...]`: the help of the tool or of one verb.
void register_help(cli::Cli& concert) {
  auto path = std::make_shared<std::vector<std::string>>();
  CLI::App& help =
      concert.verb(concert.app(), "help", "this text, or the help of a verb", [&concert, path] {
        CLI::App* app = &concert.app();
    std::string parent;  // the words before the verb, as its usage line names it
    for (const std::string& name : *path) {
      parent = parent.empty() ? app->get_name() : parent + " " + app->get_name();
      try {
        app = app->get_subcommand(name);
      } catch (const CLI::OptionNotFound&) {
        throw cli::UsageError("no verb '" + name + "' in `" + parent + "`");
      }
    }
    concert.out() << app->help(parent);
        return 0;
      });
  help.add_option("VERB", *path, "a verb, e.g. `topic echo`");
}

}  // namespace

void register_all(cli::Cli& concert) {
  concert.app().footer(kFooter);
  register_launcher_verbs(concert);
  register_status_verb(concert);
  register_topic_verbs(concert);
  register_bag_verbs(concert);
  register_scan_verbs(concert);
  register_camera_verbs(concert);
  register_bim_verbs(concert);
  security::register_verbs(concert);
  register_service_verbs(concert);
  register_help(concert);
}

}  // namespace concert::tool
