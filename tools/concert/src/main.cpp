// concert: the command-line front end of the CONCERT stack.
#include <iostream>
#include <string>
#include <vector>

#include "args.hpp"
#include "launcher.hpp"
#include "scan_verbs.hpp"
#include "status_verbs.hpp"
#include "topic_verbs.hpp"
#ifdef CONCERT_HAVE_DISCOVERY_CLI
#include "discovery/cli.hpp"
#endif
#ifdef CONCERT_HAVE_MODELGEN_CLI
#include "modelgen/cli.hpp"
#endif
#ifdef CONCERT_HAVE_SAFETY_CLI
#include "safety/cli.hpp"
#endif
#ifdef CONCERT_HAVE_PLANNER_CLI
#include "planner/cli.hpp"
#endif

namespace {

const char* kUsage = R"(usage: concert <verb> [arguments]

verbs:
  up [--assembly FILE] [--world FILE] [--module-db DIR ...] [--duration S]
                                                start every service on this machine (simulated robot),
                                                restart one that dies, stop all on Ctrl-C
  status [--json] [--check] [--wait-ms MS]     every service: host, state, model version and hash, refusals,
                                                last message; --check: exit 1 if a service is stopped or in
                                                error, the services disagree on the model, or one refused input
  status --until-version N [--services a,b] [--timeout-ms MS]
                                                wait until every model consumer is ready at version N
  sim assemble|swap FILE                        mount another assembly on the running simulated robot
  sim world FILE                                change the simulated world
  topic list [--json] [--wait-ms MS]            topics on the domain (ours and others'), with types,
                                                writer/reader counts and QoS
  topic info NAME [--wait-ms MS]                type, QoS, endpoints and type shape of a topic
  topic echo NAME [--count N] [--timeout-ms MS] samples as JSON, one object per line
  topic hz NAME [--count N] [--timeout-ms MS] [--json]
                                                arrival rate statistics
  discover --scan FILE [--port-order 0312|0123] [--module-db DIR ...] [--json]
                                                rebuild the module tree from an EtherCAT scan file
  scan show (--assembly F | --scan F) [--module-db DIR ...] [--json]
                                                the scan an assembly gives on the simulated bus
  scan publish (--assembly F | --scan F) [--module-db DIR ...] [--hold-ms MS]
                                                publish a scan as an EtherCAT master would (latched)
  model generate (--scan F | --tree F | --assembly F) --module-db DIR [...] --out DIR
                                                write URDF, SRDF, controller config and manifest
  model show [--timeout S]                      the live robot model: version, modules, chains, joints
  safety status | estop [--source S] [--release] | reset
                                                the safety layer: state, e-stop inputs, reset a latched stop
  plan ...                                      whole-body planning requests (see `concert plan --help`)
  help                                          this text

common options: --domain N (DDS domain id; default: CONCERT_DOMAIN_ID or 0)
exit codes: 0 success, 1 failure (not found, timed out, bad input file), 2 wrong command line
)";

}  // namespace

int main(int argc, char** argv) {
  std::vector<std::string> args(argv + 1, argv + argc);
  if (args.empty() || args[0] == "help" || args[0] == "--help" || args[0] == "-h") {
    std::cout << kUsage;
    return args.empty() ? 2 : 0;
  }
  const std::string verb = args[0];
  const std::vector<std::string> rest(args.begin() + 1, args.end());
  try {
    if (verb == "topic") return concert::cli::run_topic(rest, std::cout, std::cerr);
    if (verb == "scan") return concert::cli::run_scan(rest, std::cout, std::cerr);
    if (verb == "status") return concert::cli::run_status(rest, std::cout, std::cerr);
    if (verb == "up") return concert::cli::run_up(rest, std::cout, std::cerr);
    if (verb == "sim") return concert::cli::run_sim(rest, std::cout, std::cerr);
#ifdef CONCERT_HAVE_DISCOVERY_CLI
    if (verb == "discover") return concert::discovery::cli_main(rest, std::cout, std::cerr);
#endif
#ifdef CONCERT_HAVE_SAFETY_CLI
    if (verb == "safety") return concert::safety::cli_main(rest, std::cout, std::cerr);
#endif
#ifdef CONCERT_HAVE_PLANNER_CLI
    if (verb == "plan") return concert::planner::cli_main(rest, std::cout, std::cerr);
#endif
#ifdef CONCERT_HAVE_MODELGEN_CLI
    if (verb == "model") return concert::modelgen::cli_main(rest, std::cout, std::cerr);
#endif
    std::cerr << "concert: unknown verb '" << verb << "' (see `concert help`)\n";
    return 2;
  } catch (const concert::cli::UsageError& e) {
    std::cerr << "concert " << verb << ": " << e.what() << " (see `concert help`)\n";
    return 2;
  } catch (const std::invalid_argument& e) {
    std::cerr << "concert " << verb << ": " << e.what() << "\n";
    return 2;
  } catch (const std::exception& e) {
    std::cerr << "concert " << verb << ": " << e.what() << "\n";
    return 1;
  }
}
