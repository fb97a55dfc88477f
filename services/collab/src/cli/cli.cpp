// `concert collab say|listen|mode|status`: commands to the collab service and its state.

#include "collab/cli.hpp"

#include <chrono>
#include <memory>
#include <nlohmann/json.hpp>
#include <optional>
#include <random>

#include "collab/command_parser.hpp"
#include "collab/voice.hpp"
#include "concert/common/clock.hpp"
#include "concert/common/resend.hpp"
#include "concert/dds/endpoint.hpp"
#include "concert/dds/participant.hpp"

namespace concert::collab {
namespace {

namespace cdds = concert::dds;
using Clock = std::chrono::steady_clock;

std::chrono::milliseconds left_until(Clock::time_point deadline) {
  return std::max(std::chrono::milliseconds(0),
                  std::chrono::duration_cast<std::chrono::milliseconds>(deadline - Clock::now()));
}

nlohmann::ordered_json state_json(const msg::CollabState& s) {
  return {{"state", s.state()},
          {"estop", s.estop()},
          {"model_version", s.model_version()},
          {"command_id", s.command_id()},
          {"command", s.command()},
          {"accepted", s.accepted()},
          {"reason", s.reason()},
          {"command_latency_s", s.command_latency()},
          {"base_velocity", {s.base_velocity().linear().x(), s.base_velocity().linear().y(), s.base_velocity().angular().z()}},
          {"ee_force", {s.ee_force().x(), s.ee_force().y(), s.ee_force().z()}},
          {"active_obstacles", s.active_obstacles()},
          {"mpc_solve_ms", s.mpc_solve_ms()}};
}

void print_state(const msg::CollabState& s, bool json, std::ostream& out) {
  if (json) {
    out << state_json(s).dump() << std::endl;
    return;
  }
  out << "state " << s.state() << (s.estop() ? " (safety stop active)" : "") << ", model version "
      << s.model_version() << "\n";
  if (!s.command().empty())
    out << "last command \"" << s.command() << "\": " << (s.accepted() ? "accepted" : "ignored")
        << (s.reason().empty() ? "" : " (" + s.reason() + ")") << "\n";
}

// Sends one command and waits for the state that answers it.
int send(cdds::Participant& participant, const std::string& text, bool direct, const std::string& source,
         const cli::DdsOptions& dds, std::ostream& out, std::ostream& err) {
  cdds::Reader<msg::CollabState> states(participant, cdds::topics::collab_state);
  cdds::Writer<msg::CollabCommand> commands(participant, cdds::topics::collab_command);
  const auto deadline = Clock::now() + dds.timeout();
  if (!commands.wait_for_readers(1, std::min(left_until(deadline), std::chrono::milliseconds(5000)))) {
    err << "concert collab: no collab service listening on domain " << participant.domain_id()
        << " (is concert_collab running?)\n";
    return 1;
  }
  std::mt19937 rng(static_cast<unsigned>(now_ns()));
  msg::CollabCommand c;
  c.command_id(std::uniform_int_distribution<std::uint32_t>(1, 0x7fffffff)(rng));
  c.stamp_ns(now_ns());
  c.source(source);
  c.text(text);
  c.direct(direct);
  // The reader matched first may be another tool's (the GUI's gateway, a recorder) before the
  // collab service's: the command is written again every second until the state answering it
  // comes (the service takes a command it has seen, same id and stamp, once).
  std::optional<msg::CollabState> answer;
  resend_until_answered([&] { commands.write(c); },
                        [&](Clock::time_point until) {
                          while (!answer && Clock::now() < until) {
                            const auto s = states.wait(left_until(until));
                            if (s && s->command_id() == c.command_id()) answer = s;
                          }
                          return answer.has_value();
                        },
                        deadline);
  if (!answer) {
    err << "concert collab: the collab service did not answer within " << dds.timeout_s << " s\n";
    return 1;
  }
  print_state(*answer, dds.json, out);
  return answer->accepted() ? 0 : 1;
}

bool known_mode(const std::string& m) {
  if (m == "follow-me" || m == "follow_me") return true;
  for (Command c : kAllCommands)
    if (m == command_phrase(c) && c != Command::kFollowMe) return true;
  return false;
}

struct ListenOptions {
  std::string wav;
  bool dry_run{false};
  cli::DdsOptions dds;
};

int run_listen(const ListenOptions& o, std::ostream& out, std::ostream& err) {
  std::vector<std::int16_t> audio;
  try {
    audio = load_audio_16k(o.wav);
  } catch (const std::exception& e) {
    err << "concert collab listen: " << e.what() << "\n";
    return 2;
  }
  VoiceRecognizer recogniser;
  const auto utterances = split_utterances(audio);
  if (utterances.empty()) {
    out << "no speech in " << o.wav << "\n";
    return 1;
  }
  std::unique_ptr<cdds::Participant> participant;
  int sent = 0, failed = 0;
  for (std::size_t i = 0; i < utterances.size(); ++i) {
    const auto r = recogniser.recognise(utterances[i]);
    out << "utterance " << i + 1 << ": heard \"" << r.hypothesis << "\" -> "
        << (r.command ? std::string("command ") + command_name(*r.command) : "rejected: " + r.reason)
        << "  (" << static_cast<int>(r.decode_ms) << " ms)\n";
    if (!r.command || o.dry_run) continue;
    if (!participant)
      participant = std::make_unique<cdds::Participant>(
          cdds::ParticipantOptions{.name = "concert_collab", .domain_id = o.dds.domain_id()});
    ++sent;
    if (send(*participant, std::string("hey concert ") + command_phrase(*r.command), false, "voice", o.dds, out,
             err) != 0)
      ++failed;
  }
  return (o.dry_run || (sent > 0 && failed == 0)) ? 0 : 1;
}

int run_status(const cli::DdsOptions& dds, std::ostream& out, std::ostream& err) {
  cdds::Participant participant({.name = "concert_collab", .domain_id = dds.domain_id()});
  cdds::Reader<msg::CollabState> states(participant, cdds::topics::collab_state);
  const auto s = states.wait(dds.timeout());
  if (!s) {
    err << "concert collab status: no collab state on domain " << participant.domain_id()
        << " (is concert_collab running?)\n";
    return 1;
  }
  print_state(*s, dds.json, out);
  return 0;
}

}  // namespace

void register_verbs(cli::Cli& concert) {
  CLI::App& collab = concert.group(concert.app(), "collab", "collaborative transportation (collab service)");
  {
    auto text = std::make_shared<std::string>();
    auto dds = std::make_shared<cli::DdsOptions>();
    CLI::App& verb = concert.verb(collab, "say", "send a spoken command as text (\"hey concert follow me\")",
                                  [&concert, text, dds] {
                                    cdds::Participant p({.name = "concert_collab", .domain_id = dds->domain_id()});
                                    return send(p, *text, false, "cli", *dds, concert.out(), concert.err());
                                  });
    verb.add_option("text", *text, "what is said, with the wake phrase")->required();
    concert.add_dds_options(verb, *dds, 5.0, "how long to wait for the collab service");
  }
  {
    auto o = std::make_shared<ListenOptions>();
    CLI::App& verb = concert.verb(collab, "listen", "recognise the voice commands in a WAV file and send them",
                                  [&concert, o] { return run_listen(*o, concert.out(), concert.err()); });
    verb.add_option("--wav", o->wav, "audio file (any rate, mono or stereo)")->required()->type_name("FILE");
    verb.add_flag("--dry-run", o->dry_run, "recognise only, send nothing");
    concert.add_dds_options(verb, o->dds, 5.0, "how long to wait for the collab service per command");
  }
  {
    auto mode = std::make_shared<std::string>();
    auto dds = std::make_shared<cli::DdsOptions>();
    CLI::App& verb = concert.verb(collab, "mode", "switch mode or act as the GUI's buttons do (no wake phrase)",
                                  [&concert, mode, dds] {
                                    // Checked here, not by the parser: the verb tree's test
                                    // walks every verb with placeholder arguments.
                                    if (!known_mode(*mode)) {
                                      concert.err() << "concert collab mode: unknown mode \"" << *mode
                                                    << "\" (teaching, autonomous, follow-me, stop, open, "
                                                       "close, lift or place)\n";
                                      return 2;
                                    }
                                    cdds::Participant p({.name = "concert_collab", .domain_id = dds->domain_id()});
                                    return send(p, *mode, true, "gui", *dds, concert.out(), concert.err());
                                  });
    verb.add_option("mode", *mode, "teaching | autonomous | follow-me | stop | open | close | lift | place")
        ->required();
    concert.add_dds_options(verb, *dds, 5.0, "how long to wait for the collab service");
  }
  {
    auto dds = std::make_shared<cli::DdsOptions>();
    CLI::App& verb = concert.verb(collab, "status", "the state, the last command and its result",
                                  [&concert, dds] { return run_status(*dds, concert.out(), concert.err()); });
    concert.add_dds_options(verb, *dds, 3.0, "how long to wait for the collab service's state");
  }
}

}  // namespace concert::collab
