#include "gui/cli.hpp"

#include <termios.h>
#include <unistd.h>

#include <iostream>
#include <memory>

#include "concert/cli/stop_signals.hpp"

namespace concert::gui {

void add_gateway_options(CLI::App& app, GatewayOptions& o) {
  app.add_option("--port", o.port, "TCP port of the app and its WebSocket API (0: any free port)")
      ->type_name("N")
      ->check(cli::number(0, 65535, true))
      ->default_str("8080 + domain");
  app.add_option("--bind", o.bind,
                 "address to listen on; the default serves this machine only, 0.0.0.0 the robot's "
                 "network (then HTTPS and sign-in are required)")
      ->type_name("ADDR")
      ->default_str(o.bind);
  app.add_option("--tls", o.tls_dir,
                 "serve HTTPS/WSS with the certificate of a PKI folder made by `concert security init` "
                 "(DIR/gui/https_cert.pem, https_key.pem)")
      ->type_name("DIR");
  app.add_option("--tls-cert", o.tls_certificate, "serve HTTPS/WSS with this PEM certificate (the site's; chain after it)")
      ->type_name("FILE");
  app.add_option("--tls-key", o.tls_key, "the PEM private key of --tls-cert")->type_name("FILE");
  app.add_flag("--auth", o.auth, "require sign-in on a loopback bind too (always required beyond it)");
  app.add_option("--users", o.users_file, "the users file (concert gui users)")
      ->type_name("FILE")
      ->default_str(default_users_file());
  app.add_flag("--pairing", o.pairing,
               "print a one-time pairing code in the log: a tablet signs in with it as an operator");
  app.add_option("--session-hours", o.auth_params.session_ttl_s, "a session ends this long after sign-in")
      ->type_name("H")
      ->check(cli::number(1, 24 * 30, true))
      ->transform([](const std::string& h) { return std::to_string(std::stoll(h) * 3600); })
      ->default_str("12");
  app.add_option("--app", o.app_dir, "the built app's folder (default: the build tree's)")->type_name("DIR");
  app.add_option("--module-db", o.module_dbs,
                 "module database folder whose meshes the 3D view loads (package://<folder name>/...; "
                 "repeat for several)")
      ->type_name("DIR");
  app.add_option("--stream-hz", o.hub.stream_max_hz, "the most samples a second a browser gets of a stream")
      ->type_name("HZ")
      ->check(cli::number(0.1, 1000.0))
      ->default_str(std::to_string(o.hub.stream_max_hz));
  app.add_option("--image-hz", o.hub.image_max_hz, "the most camera frames a second a browser gets")
      ->type_name("HZ")
      ->check(cli::number(0.1, 60.0))
      ->default_str(std::to_string(o.hub.image_max_hz));
  app.add_option("--jpeg-quality", o.jpeg.quality, "JPEG quality of camera frames (1-100)")
      ->type_name("Q")
      ->check(cli::number(1, 100, true));
}

namespace {

/// A password from standard input (one line; `concert gui users add` reads it so it never
/// appears in a command line or the shell's history). The terminal's echo is off when it is one.
std::string read_password(std::istream& in, std::ostream& err) {
  const bool tty = ::isatty(STDIN_FILENO) != 0;
  termios old{};
  if (tty) {
    err << "password: " << std::flush;
    ::tcgetattr(STDIN_FILENO, &old);
    termios quiet = old;
    quiet.c_lflag &= ~static_cast<tcflag_t>(ECHO);
    ::tcsetattr(STDIN_FILENO, TCSANOW, &quiet);
  }
  std::string password;
  std::getline(in, password);
  if (tty) {
    ::tcsetattr(STDIN_FILENO, TCSANOW, &old);
    err << std::endl;
  }
  if (!password.empty() && password.back() == '\r') password.pop_back();
  return password;
}

struct UsersOptions {
  std::string file;
  std::string name;
  std::string role = "operator";
  bool json = false;
};

}  // namespace

void register_verbs(cli::Cli& concert) {
  auto o = std::make_shared<GatewayOptions>();
  auto dds = std::make_shared<cli::DdsOptions>();
  CLI::App& verb = concert.verb(concert.app(), "gui",
                                "the operator GUI: serve the web app and bridge it to DDS until Ctrl-C",
                                [&concert, o, dds] {
                                  o->domain_id = dds->domain_id();
                                  o->duration_s = dds->timeout_s;
                                  o->json = dds->json;
                                  return run_gateway(*o, cli::stop_on_signals(), concert.out(), concert.err());
                                });
  add_gateway_options(verb, *o);
  concert.add_dds_options(verb, *dds, 0.0, "serve this long, then stop (0: until Ctrl-C)");

  // concert gui users add|remove|list: the people who may sign in on this robot.
  CLI::App& users = concert.group(verb, "users", "who may sign in to the GUI: users and their roles");
  const auto file_option = [](CLI::App& app, UsersOptions& u) {
    app.add_option("--users", u.file, "the users file")->type_name("FILE")->default_str(default_users_file());
  };
  auto add = std::make_shared<UsersOptions>();
  CLI::App& add_verb = concert.verb(users, "add", "add a user (or set their role and password); the password is read from standard input",
                                    [&concert, add] {
                                      const std::string file = add->file.empty() ? default_users_file() : add->file;
                                      UserStore store = UserStore::load(file);
                                      const auto role = role_from_string(add->role);
                                      const std::string password = read_password(std::cin, concert.err());
                                      store.add(add->name, *role, password);
                                      store.save(file);
                                      concert.out() << "concert gui users: " << add->name << " (" << add->role
                                                    << ") in " << file << std::endl;
                                      return 0;
                                    });
  add_verb.add_option("NAME", add->name, "the user's name (1-32 of A-Z a-z 0-9 . _ -)")->required();
  cli::Cli::add_choice(add_verb, "--role", add->role, {"viewer", "operator", "engineer"},
                       "viewer: sees, e-stop only; operator: missions, transport, reset; engineer: hot swap, homing, add-ons");
  file_option(add_verb, *add);
  auto rm = std::make_shared<UsersOptions>();
  CLI::App& rm_verb = concert.verb(users, "remove", "remove a user (their open sessions end when the gateway restarts)",
                                   [&concert, rm] {
                                     const std::string file = rm->file.empty() ? default_users_file() : rm->file;
                                     UserStore store = UserStore::load(file);
                                     if (!store.remove(rm->name)) {
                                       concert.err() << "concert gui users remove: no user '" << rm->name << "' in "
                                                     << file << std::endl;
                                       return 1;
                                     }
                                     store.save(file);
                                     concert.out() << "concert gui users: removed " << rm->name << std::endl;
                                     return 0;
                                   });
  rm_verb.add_option("NAME", rm->name, "the user's name")->required();
  file_option(rm_verb, *rm);
  auto ls = std::make_shared<UsersOptions>();
  CLI::App& ls_verb = concert.verb(users, "list", "the users and their roles (never the hashes)", [&concert, ls] {
    const std::string file = ls->file.empty() ? default_users_file() : ls->file;
    const UserStore store = UserStore::load(file);
    Json list = Json::array();
    for (const auto& u : store.users()) list.push_back({{"name", u.name}, {"role", to_string(u.role)}});
    if (ls->json) {
      concert.out() << list.dump() << std::endl;
    } else if (store.users().empty()) {
      concert.out() << "no users in " << file << std::endl;
    } else {
      for (const auto& u : store.users()) concert.out() << u.name << "  " << to_string(u.role) << std::endl;
    }
    return 0;
  });
  file_option(ls_verb, *ls);
  ls_verb.add_flag("--json", ls->json, "one JSON array of {name, role}");
}

}  // namespace concert::gui
