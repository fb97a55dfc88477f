// The operator GUI as a site exposes it: bound beyond loopback, HTTPS with the project's CA,
// sign-in with users and roles. The project's PKI (`concert security init`) and three users
// (`concert gui users add`), then `concert up --gui-bind 0.0.0.0 --gui-tls DIR` with the drill
// robot; OpenSSL's s_client checks the chain and that TLS below 1.2 is refused; chromium, trusting
// the CA through a throwaway NSS database, runs app/test/https_test.mjs (a viewer refused, an
// operator's mission and reset, an engineer's hot swap, the e-stop for every role, 20 wrong
// passwords slowed); the gateway's log must name each command's user. Plain HTTP beyond loopback
// is refused by the gateway and by `concert up`.
#include <gtest/gtest.h>

#include <cstdlib>
#include <iostream>
#include <regex>
#include <string>
#include <thread>
#include <vector>

#include "../../../tests/system/helpers.hpp"
#include "process.hpp"

namespace concert::gui {
namespace {

using namespace std::chrono_literals;
using concert::testing::Process;
using concert::system_test::dies_with_test;

concert::testing::Outcome sh(const std::string& script, std::chrono::seconds timeout = 60s,
                             std::vector<std::string> env = {}) {
  return concert::testing::run({"/bin/sh", "-c", script}, timeout, std::move(env));
}

TEST(GuiHttps, PlainHttpBeyondLoopbackIsRefused) {
  concert::testing::TempDir dir("concert-gui-plain");
  const auto gateway = concert::testing::run(
      {CONCERT_BIN, "gui", "--bind", "0.0.0.0", "--port", "0", "--users", dir.path() + "/users.json", "--timeout", "5"}, 30s);
  EXPECT_EQ(gateway.code, 1) << gateway.out << gateway.err;
  EXPECT_NE(gateway.err.find("refused over plain HTTP"), std::string::npos) << gateway.err;
  const auto up = concert::testing::run({CONCERT_BIN, "up", "--gui-bind", "0.0.0.0", "--duration", "1"}, 30s);
  EXPECT_EQ(up.code, 2) << up.out << up.err;
  EXPECT_NE(up.err.find("--gui-tls"), std::string::npos) << up.err;
}

TEST(GuiHttps, RolesOverHttpsWithTheProjectCaInChromium) {
  concert::testing::TempDir run_dir("concert-gui-https");
  const std::string pki = run_dir.path() + "/pki";
  const std::string users = run_dir.path() + "/users.json";
  const std::string home = run_dir.path() + "/home";
  const std::vector<std::string> env{"XDG_RUNTIME_DIR=" + run_dir.path()};

  auto init = concert::testing::run({CONCERT_BIN, "security", "init", pki, "--days", "2"}, 60s);
  ASSERT_EQ(init.code, 0) << init.out << init.err;
  for (const auto& [user, role] : std::vector<std::pair<std::string, std::string>>{
           {"vera", "viewer"}, {"otto", "operator"}, {"erin", "engineer"}}) {
    const auto add = sh("printf '%s\\n' '" + role + "-password' | " CONCERT_BIN " gui users add " + user + " --role " + role +
                        " --users " + users);
    ASSERT_EQ(add.code, 0) << add.out << add.err;
  }
  const auto list = concert::testing::run({CONCERT_BIN, "gui", "users", "list", "--users", users}, 30s);
  EXPECT_EQ(list.out, "vera  viewer\notto  operator\nerin  engineer\n");

  // A tablet set up for the site: the project's CA trusted in its browser's NSS database.
  const auto nss = sh("mkdir -p '" + home + "/.pki/nssdb' && certutil -N -d 'sql:" + home +
                      "/.pki/nssdb' --empty-password && certutil -A -d 'sql:" + home +
                      "/.pki/nssdb' -n concert-ca -t C,, -i '" + pki + "/ca.pem'");
  ASSERT_EQ(nss.code, 0) << nss.out << nss.err;

  Process up(dies_with_test({CONCERT_BIN, "up", "--assembly", CONCERT_SOURCE_DIR "/deploy/demo/drill_robot.yaml", "--world",
                             CONCERT_SOURCE_DIR "/deploy/demo/drill_site.yaml", "--gui-bind", "0.0.0.0", "--gui-tls", pki,
                             "--gui-users", users}),
             env);
  const char* d = std::getenv("CONCERT_DOMAIN_ID");
  const std::string logs_dir = run_dir.path() + "/concert-d" + std::string(d ? d : "0") + "/logs";
  const auto gateway_log = [&] { return concert::testing::run({"/bin/cat", logs_dir + "/gui.log"}, 5s).out; };
  ASSERT_TRUE(up.wait_for_output("operator GUI: https://", 30s)) << up.out() << up.err();
  std::smatch m;
  const std::string out = up.out();
  ASSERT_TRUE(std::regex_search(out, m, std::regex("operator GUI: https://<this host>:([0-9]+)/"))) << out;
  const std::string port = m[1];
  auto status = concert::testing::run({CONCERT_BIN, "status", "--until-version", "1", "--timeout", "90"}, 120s, env);
  ASSERT_EQ(status.code, 0) << status.out << status.err << up.out() << up.err();

  // The gateway listens once its log says so (the supervisor starts it last; it reports no status).
  const auto deadline = std::chrono::steady_clock::now() + 60s;
  while (gateway_log().find("concert_gui: serving https://") == std::string::npos &&
         std::chrono::steady_clock::now() < deadline) {
    std::this_thread::sleep_for(100ms);
  }
  ASSERT_NE(gateway_log().find("concert_gui: serving https://"), std::string::npos) << gateway_log() << up.out();

  // OpenSSL's view: the chain verifies against the CA for localhost; TLS 1.1 is refused.
  const auto chain = sh("openssl s_client -connect 127.0.0.1:" + port + " -CAfile '" + pki +
                        "/ca.pem' -verify_return_error -verify_hostname localhost < /dev/null 2>&1");
  EXPECT_EQ(chain.code, 0) << chain.out;
  EXPECT_NE(chain.out.find("Verify return code: 0 (ok)"), std::string::npos) << chain.out;
  EXPECT_NE(chain.out.find("CN = CONCERT operator GUI"), std::string::npos) << chain.out;
  EXPECT_NE(chain.out.find("CN = CONCERT CA"), std::string::npos) << chain.out;
  const auto old = sh("openssl s_client -connect 127.0.0.1:" + port + " -tls1_1 < /dev/null 2>&1");
  EXPECT_NE(old.code, 0) << old.out;
  EXPECT_NE(old.out.find("alert protocol version"), std::string::npos) << old.out;
  const auto plain = sh("curl -s -m 10 -o /dev/null -w '%{http_code}' http://127.0.0.1:" + port + "/");
  EXPECT_EQ(plain.out, "000") << "plain HTTP on the HTTPS port got an answer";

  Process browser({"/usr/bin/nice", "-n", "15", CONCERT_NODE, CONCERT_SOURCE_DIR "/services/gui/app/test/https_test.mjs"},
                  {"GUI_URL=https://localhost:" + port + "/", "CONCERT_BIN=" CONCERT_BIN,
                   "CONCERT_SOURCE_DIR=" CONCERT_SOURCE_DIR, "SHOTS_DIR=" GUI_SCREENSHOTS, "HOME=" + home,
                   "XDG_RUNTIME_DIR=" + run_dir.path()});
  const auto code = browser.wait(420s);
  const std::string log = gateway_log();
  std::cout << "--- https_test.mjs:\n" << browser.out() << std::flush;
  ASSERT_EQ(code, 0) << "--- https_test.mjs:\n" << browser.out() << browser.err() << "\n--- gateway log:\n" << log;

  // Every command in the log with its user; the viewer's refusal too.
  EXPECT_NE(log.find("sign-in required (3 users in " + users + ")"), std::string::npos) << log;
  EXPECT_TRUE(std::regex_search(log, std::regex("command REFUSED from 127\\.0\\.0\\.1:[0-9]+ \\(client [0-9]+, user vera/viewer\\) "
                                                "on concert/drill/mission: role viewer may not command")))
      << log;
  for (const auto& who : {"vera/viewer", "otto/operator", "erin/engineer"}) {
    EXPECT_TRUE(std::regex_search(log, std::regex(std::string("command from 127\\.0\\.0\\.1:[0-9]+ \\(client [0-9]+, user ") + who +
                                                  "\\) on concert/safety/estop")))
        << who << "'s e-stop\n" << log;
  }
  EXPECT_NE(log.find("user otto/operator) on concert/drill/mission"), std::string::npos) << log;
  EXPECT_NE(log.find("user otto/operator) on concert/safety/reset"), std::string::npos) << log;
  EXPECT_NE(log.find("user erin/engineer) on concert/sim/command"), std::string::npos) << log;
  EXPECT_NE(log.find("sign-in REFUSED from 127.0.0.1"), std::string::npos) << log;
  EXPECT_NE(log.find("try again in"), std::string::npos) << log;
}

}  // namespace
}  // namespace concert::gui
