// `concert security init`: the files it writes, checked with the `openssl` command (an
// independent reader), their modes, refusing to replace a PKI, and the checks a participant runs
// before it trusts an identity's files.
#include "concert/security/pki.hpp"

#include <gmock/gmock.h>
#include <gtest/gtest.h>
#include <sys/stat.h>

#include <chrono>
#include <filesystem>
#include <fstream>
#include <sstream>

#include "concert/common/text.hpp"
#include "concert/security/cli.hpp"
#include "concert/security/table.hpp"
#include "process.hpp"

namespace concert::security {
namespace {

namespace fs = std::filesystem;
using ::testing::HasSubstr;
using namespace std::chrono_literals;

constexpr const char* kOpenssl = "/usr/bin/openssl";

testing::Outcome openssl(std::vector<std::string> args) {
  args.insert(args.begin(), kOpenssl);
  return testing::run(args, 30s);
}

mode_t mode_of(const fs::path& p) {
  struct stat st {};
  EXPECT_EQ(::stat(p.c_str(), &st), 0) << p;
  return st.st_mode & 07777;
}

void replace_in_file(const fs::path& p, const std::string& from, const std::string& to) {
  std::string text = read_file(p);
  const size_t at = text.find(from);
  ASSERT_NE(at, std::string::npos) << from << " not in " << p;
  text.replace(at, from.size(), to);
  std::ofstream(p) << text;
}

/// One PKI for the whole suite: key generation is the slow part.
class Pki : public ::testing::Test {
 protected:
  static void SetUpTestSuite() {
    dir_ = new testing::TempDir("concert-pki");
    created_ = new std::vector<CreatedFile>(init_pki(pki(), {.days = 30}));
  }
  static void TearDownTestSuite() {
    delete created_;
    delete dir_;
  }
  static fs::path pki() { return fs::path(dir_->path()) / "pki"; }
  static testing::TempDir* dir_;
  static std::vector<CreatedFile>* created_;
};
testing::TempDir* Pki::dir_ = nullptr;
std::vector<CreatedFile>* Pki::created_ = nullptr;

TEST_F(Pki, WritesTheCaAndFourFilesPerIdentityKeysPrivate) {
  // The CA's four, four per identity, the GUI's HTTPS key and certificate.
  ASSERT_EQ(created_->size(), 4 + 4 * identities().size() + 2);
  for (const auto& f : *created_) {
    ASSERT_TRUE(fs::is_regular_file(f.path)) << f.path;
    const bool key = f.path.filename() == "key.pem" || f.path.filename() == "ca_key.pem" ||
                     f.path.filename() == "https_key.pem";
    EXPECT_EQ(mode_of(f.path), key ? 0600u : 0644u) << f.path;
    EXPECT_EQ(key, f.what.find("private key") != std::string::npos) << f.what;
  }
  EXPECT_EQ(created_->front().path, pki() / "ca.pem");
  EXPECT_FALSE(fs::exists(pki() / "robot" / "key.pem.tmp"));
}

TEST_F(Pki, OpensslVerifiesEveryCertificateAgainstTheCa) {
  const std::string ca = (pki() / "ca.pem").string();
  for (const auto id : identities()) {
    const std::string cert = (pki() / std::string(id) / "cert.pem").string();
    const auto verify = openssl({"verify", "-CAfile", ca, cert});
    EXPECT_EQ(verify.code, 0) << id << ": " << verify.out << verify.err;
    const auto subject =
        openssl({"x509", "-in", cert, "-noout", "-subject", "-nameopt", "RFC2253"});
    EXPECT_EQ(subject.out, "subject=CN=" + std::string(id) + ",O=CONCERT\n");
    // The key is EC P-256 and belongs to the certificate.
    const auto key =
        openssl({"pkey", "-in", (pki() / std::string(id) / "key.pem").string(), "-pubout"});
    const auto pub = openssl({"x509", "-in", cert, "-noout", "-pubkey"});
    EXPECT_EQ(key.out, pub.out) << id;
    const auto text = openssl({"x509", "-in", cert, "-noout", "-text"});
    EXPECT_THAT(text.out, HasSubstr("ASN1 OID: prime256v1"));
    EXPECT_THAT(text.out, HasSubstr("Signature Algorithm: ecdsa-with-SHA256"));
    EXPECT_THAT(text.out, HasSubstr("CA:FALSE"));
  }
  const auto ca_text = openssl({"x509", "-in", ca, "-noout", "-text"});
  EXPECT_THAT(ca_text.out, HasSubstr("CA:TRUE"));
}

TEST_F(Pki, TheGuisHttpsCertificateIsAServerCertificateForLocalhostThatOpensslVerifies) {
  const std::string ca = (pki() / "ca.pem").string();
  const std::string cert = (pki() / "gui" / "https_cert.pem").string();
  // Verified for TLS servers (purpose sslserver) by name and by address.
  for (const std::vector<std::string>& target : {std::vector<std::string>{"-verify_hostname", "localhost"},
                                                 std::vector<std::string>{"-verify_ip", "127.0.0.1"}}) {
    std::vector<std::string> args = {"verify", "-CAfile", ca, "-purpose", "sslserver"};
    args.insert(args.end(), target.begin(), target.end());
    args.push_back(cert);
    const auto verify = openssl(args);
    EXPECT_EQ(verify.code, 0) << verify.out << verify.err;
  }
  const auto wrong = openssl({"verify", "-CAfile", ca, "-verify_hostname", "example.org", cert});
  EXPECT_NE(wrong.code, 0) << "a name it was not made for: " << wrong.out;
  const auto key = openssl({"pkey", "-in", (pki() / "gui" / "https_key.pem").string(), "-pubout"});
  const auto pub = openssl({"x509", "-in", cert, "-noout", "-pubkey"});
  EXPECT_EQ(key.out, pub.out);
  // Issued again for the site's names: the new names are in, the old key replaced.
  const auto again = issue_https_certificate(pki(), {.names = {"robot.site", "10.1.2.3"}, .days = 30});
  ASSERT_EQ(again.size(), 2u);
  const auto text = openssl({"x509", "-in", cert, "-noout", "-ext", "subjectAltName,extendedKeyUsage"});
  EXPECT_THAT(text.out, HasSubstr("DNS:robot.site"));
  EXPECT_THAT(text.out, HasSubstr("IP Address:10.1.2.3"));
  EXPECT_THAT(text.out, HasSubstr("TLS Web Server Authentication"));
  EXPECT_NE(openssl({"pkey", "-in", (pki() / "gui" / "https_key.pem").string(), "-pubout"}).out, key.out);
  EXPECT_THROW(issue_https_certificate(pki(), {.names = {"not a host;"}}), std::invalid_argument);
}

TEST_F(Pki, CertificatesAreValidForTheDaysAsked) {
  const auto end = openssl({"x509", "-in", (pki() / "robot/cert.pem").string(), "-noout",
                            "-checkend", std::to_string(29 * 24 * 3600)});
  EXPECT_EQ(end.code, 0) << "valid for 29 more days: " << end.out;
  const auto later = openssl({"x509", "-in", (pki() / "robot/cert.pem").string(), "-noout",
                              "-checkend", std::to_string(31 * 24 * 3600)});
  EXPECT_EQ(later.code, 1) << "expired within 31 days: " << later.out;
}

TEST_F(Pki, OpensslVerifiesTheSignedDocumentsAndTheyCarryThePlainText) {
  const std::string ca = (pki() / "ca.pem").string();
  std::vector<fs::path> docs = {pki() / "governance"};
  for (const auto id : identities()) docs.push_back(pki() / std::string(id) / "permissions");
  for (const auto& doc : docs) {
    const auto verify =
        openssl({"smime", "-verify", "-text", "-CAfile", ca, "-in", doc.string() + ".p7s"});
    EXPECT_EQ(verify.code, 0) << doc << ": " << verify.err;
    // S/MIME signs the canonical text (CRLF line ends); XML readers take either.
    std::string text = verify.out;
    std::erase(text, '\r');
    EXPECT_EQ(text, read_file(doc.string() + ".xml")) << doc;
  }
  EXPECT_THAT(read_file(pki() / "operator/permissions.xml"),
              HasSubstr("<topic>concert/safety/estop</topic>"));
  EXPECT_THAT(read_file(pki() / "operator/permissions.xml"),
              ::testing::Not(HasSubstr("concert/robot/joint_command")));
}

TEST_F(Pki, EveryIdentityChecksAndTamperingIsNamed) {
  for (const auto id : identities())
    EXPECT_NO_THROW(check_identity(identity_files(pki(), id))) << id;

  testing::TempDir tmp("concert-pki-copy");
  const fs::path copy = fs::path(tmp.path()) / "pki";
  fs::copy(pki(), copy, fs::copy_options::recursive);
  // The operator grants itself the joint commands: the signature no longer verifies.
  replace_in_file(copy / "operator/permissions.p7s", "<topic>concert/safety/estop</topic>",
                  "<topic>concert/robot/joint_command</topic>");
  try {
    check_identity(identity_files(copy, "operator"));
    ADD_FAILURE() << "tampered permissions accepted";
  } catch (const std::runtime_error& e) {
    EXPECT_THAT(e.what(), HasSubstr("permissions of operator '" +
                                    (copy / "operator/permissions.p7s").string() +
                                    "': the signature does not verify"));
  }
  // The planner's files handed to another identity: the grant names another subject.
  fs::copy_file(copy / "planner/permissions.p7s", copy / "nav/permissions.p7s",
                fs::copy_options::overwrite_existing);
  try {
    check_identity(identity_files(copy, "nav"));
    ADD_FAILURE() << "permissions of another identity accepted";
  } catch (const std::runtime_error& e) {
    EXPECT_THAT(e.what(),
                HasSubstr("are granted to 'CN=planner,O=CONCERT', not to the certificate's "
                          "subject 'CN=nav,O=CONCERT'"));
  }
  fs::remove(copy / "drill/key.pem");
  try {
    check_identity(identity_files(copy, "drill"));
    ADD_FAILURE() << "missing key accepted";
  } catch (const std::runtime_error& e) {
    EXPECT_THAT(e.what(), HasSubstr("private key of drill '" + (copy / "drill/key.pem").string() +
                                    "' cannot be read (missing"));
  }
}

TEST_F(Pki, RefusesToReplaceAPkiUnlessForcedAndThenOldIdentitiesFail) {
  testing::TempDir tmp("concert-pki-force");
  const fs::path dir = fs::path(tmp.path()) / "pki";
  fs::copy(pki(), dir, fs::copy_options::recursive);
  const std::string before = read_file(dir / "ca.pem");
  try {
    init_pki(dir);
    ADD_FAILURE() << "an existing PKI was replaced";
  } catch (const std::runtime_error& e) {
    EXPECT_THAT(e.what(), HasSubstr("'" + dir.string() + "' already holds a PKI ('" +
                                    (dir / "ca.pem").string() + "' exists): give --force"));
  }
  EXPECT_EQ(read_file(dir / "ca.pem"), before);
  // A CA key or identity left over from a partial run counts too.
  testing::TempDir partial("concert-pki-partial");
  fs::create_directories(fs::path(partial.path()) / "safety");
  std::ofstream(fs::path(partial.path()) / "safety/key.pem") << "old";
  EXPECT_THROW(init_pki(partial.path()), std::runtime_error);

  const fs::path old_robot = fs::path(tmp.path()) / "old_robot_cert.pem";
  fs::copy_file(dir / "robot/cert.pem", old_robot);
  init_pki(dir, {.days = 2, .force = true});
  EXPECT_NE(read_file(dir / "ca.pem"), before);
  EXPECT_EQ(mode_of(dir / "robot/key.pem"), 0600u);
  EXPECT_NO_THROW(check_identity(identity_files(dir, "robot")));
  fs::copy_file(old_robot, dir / "robot/cert.pem", fs::copy_options::overwrite_existing);
  try {
    check_identity(identity_files(dir, "robot"));
    ADD_FAILURE() << "a certificate of the replaced CA accepted";
  } catch (const std::runtime_error& e) {
    EXPECT_THAT(e.what(),
                HasSubstr("certificate of robot '" + (dir / "robot/cert.pem").string() + "': "));
  }
  EXPECT_THROW(init_pki(dir, {.days = 0, .force = true}), std::invalid_argument);
}

TEST_F(Pki, GuidPrefixesFollowTheSubjectHash) {
  const auto h = subject_hash(pki() / "robot/cert.pem");
  ASSERT_EQ(h.size(), 32u);
  // Same subject in another PKI: same hash (it depends on the name only).
  testing::TempDir tmp("concert-pki-hash");
  init_pki(tmp.path(), {.days = 1});
  EXPECT_EQ(subject_hash(fs::path(tmp.path()) / "robot/cert.pem"), h);
  EXPECT_NE(subject_hash(pki() / "planner/cert.pem"), h);
}

int run_cli(const std::vector<std::string>& args, std::string& out, std::string& err) {
  std::ostringstream o, e;
  const int code = cli::run("concert", {register_verbs}, args, o, e);
  out = o.str();
  err = e.str();
  return code;
}

TEST(SecurityCli, InitPrintsWhatItCreatedRefusesTwiceChecksAndPrintsTheTable) {
  testing::TempDir tmp("concert-pki-cli");
  const std::string dir = tmp.path() + "/pki";
  std::string out, err;
  ASSERT_EQ(run_cli({"security", "init", dir, "--days", "10"}, out, err), 0) << err;
  EXPECT_THAT(out, HasSubstr("created " + dir + "/robot/key.pem  (private key of robot)"));
  EXPECT_THAT(out, HasSubstr("PKI for 10 identities (robot, safety, discovery, modelgen, planner, "
                             "nav, drill, collab, surface_finish, operator)"));
  EXPECT_THAT(out, HasSubstr("Run the stack secured with CONCERT_SECURITY=" + dir));
  EXPECT_EQ(err, "");
  EXPECT_EQ(split(out, '\n').size(), 4 + 4 * identities().size() + 2 + 2);  // + the GUI's HTTPS pair
  EXPECT_THAT(out, HasSubstr("created " + dir + "/gui/https_cert.pem  (HTTPS certificate of the GUI (DNS:localhost,IP:127.0.0.1"));

  EXPECT_EQ(run_cli({"security", "init", dir}, out, err), 1);
  EXPECT_THAT(err, HasSubstr("already holds a PKI"));
  EXPECT_THAT(err, HasSubstr("--force"));
  EXPECT_EQ(run_cli({"security", "init", dir, "--days", "0"}, out, err), 2);
  EXPECT_THAT(err, HasSubstr("--days"));
  EXPECT_EQ(run_cli({"security", "init"}, out, err), 2);

  ASSERT_EQ(run_cli({"security", "check", dir}, out, err), 0) << err;
  EXPECT_THAT(out, HasSubstr("operator: ok, valid until "));
  std::filesystem::remove(dir + "/safety/permissions.p7s");
  EXPECT_EQ(run_cli({"security", "check", dir}, out, err), 1);
  EXPECT_THAT(err, HasSubstr("concert security check: safety: permissions of safety '" + dir +
                             "/safety/permissions.p7s' cannot be read (missing"));
  EXPECT_EQ(run_cli({"security", "check", dir, "--identity", "robot"}, out, err), 0) << err;
  EXPECT_EQ(run_cli({"security", "check", dir, "--identity", "root"}, out, err), 2);

  ASSERT_EQ(run_cli({"security", "table"}, out, err), 0);
  EXPECT_THAT(out, HasSubstr("  concert/robot/joint_state         robot\n"));
  EXPECT_THAT(out, HasSubstr("  concert/robot/joint_command       planner, nav, drill, collab, surface_finish\n"));
  ASSERT_EQ(run_cli({"security", "table", "--json"}, out, err), 0);
  EXPECT_THAT(
      out,
      HasSubstr(
          R"({"topic":"concert/safety/estop","writers":["operator"],"why":"only operator tools write e-stop inputs"})"));
}

}  // namespace
}  // namespace concert::security
