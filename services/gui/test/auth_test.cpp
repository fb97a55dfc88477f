// Sign-in for the operator GUI: the user file (argon2id hashes, 0600, bad files named), password
// and pairing sign-in, sessions that expire, and wrong attempts slowed per address.
#include "gui/auth.hpp"

#include <gmock/gmock.h>
#include <gtest/gtest.h>
#include <sys/stat.h>

#include <fstream>

#include "process.hpp"

namespace concert::gui {
namespace {

using ::testing::HasSubstr;
namespace fs = std::filesystem;
constexpr int64_t kS = 1'000'000'000;

UserStore crew() {
  UserStore s;
  s.add("vera", Role::kViewer, "viewer-password");
  s.add("otto", Role::kOperator, "operator-password");
  s.add("erin", Role::kEngineer, "engineer-password");
  return s;
}

TEST(UserStore, HashesWithArgon2idAndVerifiesOnlyTheRightPassword) {
  const UserStore s = crew();
  ASSERT_EQ(s.users().size(), 3u);
  for (const auto& u : s.users()) {
    EXPECT_EQ(u.hash.rfind("$argon2id$v=19$", 0), 0u) << u.hash;
    EXPECT_EQ(u.hash.find("password"), std::string::npos);
  }
  EXPECT_EQ(s.verify("otto", "operator-password"), Role::kOperator);
  EXPECT_EQ(s.verify("otto", "engineer-password"), std::nullopt);
  EXPECT_EQ(s.verify("nobody", "operator-password"), std::nullopt);
  // Two hashes of one password differ (a random salt each).
  UserStore t;
  t.add("a", Role::kViewer, "same-password");
  t.add("b", Role::kViewer, "same-password");
  EXPECT_NE(t.users()[0].hash, t.users()[1].hash);
}

TEST(UserStore, RefusesBadNamesAndShortPasswords) {
  UserStore s;
  EXPECT_THROW(s.add("", Role::kViewer, "long enough"), UserError);
  EXPECT_THROW(s.add("a b", Role::kViewer, "long enough"), UserError);
  EXPECT_THROW(s.add(std::string(33, 'a'), Role::kViewer, "long enough"), UserError);
  try {
    s.add("ok", Role::kViewer, "short");
    FAIL();
  } catch (const UserError& e) {
    EXPECT_THAT(e.what(), HasSubstr("at least 8"));
  }
}

TEST(UserStore, SavesPrivatelyLoadsBackAndNamesWhatIsWrongInAFile) {
  concert::testing::TempDir dir("gui-users");
  const fs::path file = fs::path(dir.path()) / "sub" / "users.json";
  EXPECT_TRUE(UserStore::load(file).users().empty()) << "no file: no users";
  UserStore s = crew();
  s.save(file);
  struct stat st {};
  ASSERT_EQ(::stat(file.c_str(), &st), 0);
  EXPECT_EQ(st.st_mode & 0777, 0600u);
  const UserStore back = UserStore::load(file);
  ASSERT_EQ(back.users().size(), 3u);
  EXPECT_EQ(back.verify("erin", "engineer-password"), Role::kEngineer);
  EXPECT_TRUE(s.remove("vera"));
  EXPECT_FALSE(s.remove("vera"));
  s.save(file);
  EXPECT_EQ(UserStore::load(file).users().size(), 2u);

  const auto refused = [&](const std::string& text, const std::string& why) {
    std::ofstream(file) << text;
    try {
      (void)UserStore::load(file);
      ADD_FAILURE() << "accepted: " << text;
    } catch (const UserError& e) {
      EXPECT_THAT(e.what(), HasSubstr(file.string()));
      EXPECT_THAT(e.what(), HasSubstr(why));
    }
  };
  refused("{", "not JSON");
  refused("[]", "expected {\"users\"");
  refused(R"({"users": [{"name": "x", "role": "boss", "hash": "$argon2id$v=19$m=1"}]})", "role 'boss'");
  refused(R"({"users": [{"name": "x", "role": "viewer", "hash": "plain"}]})", "not an argon2id");
  refused(R"({"users": [{"name": "x y", "role": "viewer", "hash": "$argon2id$"}]})", "users[0]");
}

TEST(Auth, PasswordSignInGivesASessionWithTheUsersRoleThatExpires) {
  Auth auth(crew(), AuthParams{.session_ttl_s = 60});
  const Session s = auth.sign_in("10.0.0.5", "otto", "operator-password", 100 * kS);
  EXPECT_EQ(s.user, "otto");
  EXPECT_EQ(s.role, Role::kOperator);
  EXPECT_EQ(s.token.size(), 64u);
  EXPECT_EQ(s.expires_ns, 160 * kS);
  ASSERT_TRUE(auth.session(s.token, 159 * kS));
  EXPECT_FALSE(auth.session(s.token, 160 * kS)) << "expired";
  // A reloaded page resumes with its token, until it expires.
  EXPECT_EQ(auth.resume("10.0.0.5", s.token, 150 * kS).user, "otto");
  EXPECT_THROW(auth.resume("10.0.0.5", s.token, 161 * kS), SignInRefused);
  const Session other = auth.sign_in("10.0.0.5", "otto", "operator-password", 100 * kS);
  EXPECT_NE(other.token, s.token);
  auth.sign_out(other.token);
  EXPECT_FALSE(auth.session(other.token, 101 * kS));
  EXPECT_THROW(auth.sign_in("10.0.0.5", "otto", "wrong", 100 * kS), SignInRefused);
}

TEST(Auth, TwentyWrongPasswordsFromOneAddressAreSlowedOthersAreNot) {
  Auth auth(crew(), AuthParams{});  // 5 free, then 1 s doubling to 60 s
  int checked = 0, slowed = 0;
  double last_wait = 0;
  for (int i = 0; i < 20; ++i) {
    try {
      auth.sign_in("192.168.1.66", "otto", "guess-" + std::to_string(i), 1000 * kS);  // the same instant
      FAIL() << "a wrong password signed in";
    } catch (const SignInRefused& e) {
      if (std::string(e.what()).find("try again in") != std::string::npos) {
        ++slowed;
        last_wait = e.retry_after_s;
      } else {
        ++checked;
      }
    }
  }
  EXPECT_EQ(checked, 5) << "the first five are checked";
  EXPECT_EQ(slowed, 15) << "the rest are refused unchecked until the wait is over";
  EXPECT_GE(last_wait, 1.0);
  // Even the right password is refused while the address waits...
  EXPECT_THROW(auth.sign_in("192.168.1.66", "otto", "operator-password", 1000 * kS), SignInRefused);
  // ...another address is not slowed...
  EXPECT_EQ(auth.sign_in("192.168.1.67", "otto", "operator-password", 1000 * kS).role, Role::kOperator);
  // ...and after the wait, one more wrong attempt doubles it.
  try {
    auth.sign_in("192.168.1.66", "otto", "again wrong", 1002 * kS);
    FAIL();
  } catch (const SignInRefused& e) {
    EXPECT_EQ(e.retry_after_s, 2.0);
  }
  // The right password after the wait signs in and clears the count.
  EXPECT_EQ(auth.sign_in("192.168.1.66", "otto", "operator-password", 1005 * kS).user, "otto");
  EXPECT_THROW(auth.sign_in("192.168.1.66", "otto", "x", 1005 * kS), SignInRefused);
  EXPECT_EQ(auth.sign_in("192.168.1.66", "erin", "engineer-password", 1005 * kS).role, Role::kEngineer)
      << "one wrong attempt after a success is free again";
}

TEST(Auth, APairingCodeWorksOnceAndExpires) {
  Auth auth(UserStore{}, AuthParams{.pairing_role = Role::kOperator, .pairing_ttl_s = 600});
  EXPECT_FALSE(auth.pairing_open(0));
  const std::string code = auth.new_pairing_code(0);
  ASSERT_EQ(code.size(), 8u);
  EXPECT_TRUE(auth.pairing_open(599 * kS));
  EXPECT_THROW(auth.pair("10.0.0.7", "00000000" == code ? "11111111" : "00000000", kS), SignInRefused);
  const Session s = auth.pair("10.0.0.7", code, 2 * kS);
  EXPECT_EQ(s.role, Role::kOperator);
  EXPECT_EQ(s.user, "paired@10.0.0.7");
  EXPECT_THROW(auth.pair("10.0.0.8", code, 3 * kS), SignInRefused) << "once";
  const std::string late = auth.new_pairing_code(0);
  EXPECT_THROW(auth.pair("10.0.0.9", late, 601 * kS), SignInRefused) << "expired";
}

TEST(Auth, AddressesAreTakenFromOrigins) {
  EXPECT_EQ(address_of("192.168.1.20:51544"), "192.168.1.20");
  EXPECT_EQ(address_of("[::1]:8080"), "::1");
  EXPECT_EQ(address_of("host"), "host");
  EXPECT_EQ(role_from_string("engineer"), Role::kEngineer);
  EXPECT_EQ(role_from_string("root"), std::nullopt);
}

}  // namespace
}  // namespace concert::gui
