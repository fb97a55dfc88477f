#include "concert/security/cli.hpp"

#include <memory>
#include <nlohmann/json.hpp>

#include "concert/common/text.hpp"
#include "concert/dds/catalogue.hpp"
#include "concert/security/pki.hpp"
#include "concert/security/table.hpp"

namespace concert::security {
namespace {

struct Options {
  std::string dir;
  int days = 365;
  bool force = false;
  bool json = false;
  std::string identity;
  std::vector<std::string> names;
};

int init(const Options& o, std::ostream& out, std::ostream& err) {
  const auto created = init_pki(o.dir, {.days = o.days, .force = o.force});
  for (const auto& f : created) out << "created " << f.path.string() << "  (" << f.what << ")\n";
  for (const auto& t : dds::catalogue()) {
    if (writers_of(t.name).empty()) {
      err << "concert security init: warning: no identity may publish " << t.name
          << " (the topic is not in libs/security/src/table.cpp)\n";
    }
  }
  out << "PKI for " << identities().size() << " identities (" << join(identities(), ", ")
      << ") valid until " << certificate_expiry(std::filesystem::path(o.dir) / "ca.pem") << ".\n"
      << "Run the stack secured with CONCERT_SECURITY=" << std::filesystem::absolute(o.dir).string()
      << "; keep " << (std::filesystem::path(o.dir) / "ca_key.pem").string()
      << " off the robot once its identities are deployed.\n";
  return 0;
}

int https(const Options& o, std::ostream& out) {
  const auto created = issue_https_certificate(o.dir, {.names = o.names, .days = o.days});
  for (const auto& f : created) out << "created " << f.path.string() << "  (" << f.what << ")\n";
  out << "Serve the GUI with it: concert gui --bind ADDR --tls " << std::filesystem::absolute(o.dir).string()
      << " (tablets trust " << (std::filesystem::path(o.dir) / "ca.pem").string() << ").\n";
  return 0;
}

int table(const Options& o, std::ostream& out) {
  if (o.json) {
    nlohmann::ordered_json rows = nlohmann::ordered_json::array();
    for (const auto& r : write_rules()) {
      rows.push_back(
          {{"topic", r.topic},
           {"writers", std::vector<std::string_view>(r.writers.begin(), r.writers.end())},
           {"why", r.why}});
    }
    out << rows.dump() << "\n";
    return 0;
  }
  out << "Who may publish what (every identity may read every topic):\n";
  for (const auto& r : write_rules()) {
    out << "  " << r.topic << std::string(r.topic.size() < 34 ? 34 - r.topic.size() : 1, ' ')
        << join(r.writers, ", ") << "\n";
  }
  return 0;
}

int check(const Options& o, std::ostream& out, std::ostream& err) {
  std::vector<std::string_view> ids;
  if (o.identity.empty()) {
    ids.assign(identities().begin(), identities().end());
  } else {
    ids.push_back(o.identity);
  }
  int bad = 0;
  for (const auto id : ids) {
    const IdentityFiles files = identity_files(o.dir, id);
    try {
      check_identity(files);
      out << id << ": ok, valid until " << certificate_expiry(files.certificate) << "\n";
    } catch (const std::exception& e) {
      err << "concert security check: " << id << ": " << e.what() << "\n";
      ++bad;
    }
  }
  return bad == 0 ? 0 : 1;
}

}  // namespace

void register_verbs(cli::Cli& concert) {
  CLI::App& security =
      concert.group(concert.app(), "security",
                    "DDS Security: the PKI, who may publish what (CONCERT_SECURITY=DIR)");
  auto o = std::make_shared<Options>();
  CLI::App& init_verb =
      concert.verb(security, "init",
                   "create the PKI: a CA, one identity per service and "
                   "one for the operator's tools, signed governance and permissions",
                   [&concert, o] { return init(*o, concert.out(), concert.err()); });
  init_verb.add_option("DIR", o->dir, "the folder to create it in")->required()->type_name("DIR");
  init_verb.add_flag("--force", o->force, "replace a PKI already in DIR (a new CA)");
  init_verb
      .add_option("--days", o->days, "validity of the certificates and permissions (default 365)")
      ->type_name("N")
      ->check(cli::number(1, 3650, true));

  auto h = std::make_shared<Options>();
  CLI::App& https_verb =
      concert.verb(security, "https",
                   "a new HTTPS certificate for the operator GUI (DIR/gui/https_cert.pem), signed by DIR's CA, "
                   "for the names tablets reach the robot at",
                   [&concert, h] { return https(*h, concert.out()); });
  https_verb.add_option("DIR", h->dir, "a folder made by `concert security init`")->required()->type_name("DIR");
  https_verb.add_option("--name", h->names, "a host name or IP address of the robot (repeat; localhost is always in)")
      ->type_name("HOST");
  https_verb.add_option("--days", h->days, "validity (default 365)")->type_name("N")->check(cli::number(1, 3650, true));

  auto t = std::make_shared<Options>();
  CLI::App& table_verb = concert.verb(security, "table", "who may publish what",
                                      [&concert, t] { return table(*t, concert.out()); });
  table_verb.add_flag("--json", t->json, "one JSON array of {topic, writers}");

  auto c = std::make_shared<Options>();
  CLI::App& check_verb =
      concert.verb(security, "check", "check the identities' files: signatures, dates, grants",
                   [&concert, c] { return check(*c, concert.out(), concert.err()); });
  check_verb.add_option("DIR", c->dir, "a folder made by `concert security init`")
      ->required()
      ->type_name("DIR");
  std::vector<std::string> names(identities().begin(), identities().end());
  cli::Cli::add_choice(check_verb, "--identity", c->identity, names, "only this identity");
}

}  // namespace concert::security
