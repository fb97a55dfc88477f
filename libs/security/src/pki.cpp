#include "concert/security/pki.hpp"

#include <arpa/inet.h>
#include <unistd.h>

#include <algorithm>
#include <cctype>

#include <fcntl.h>
#include <openssl/bn.h>
#include <openssl/err.h>
#include <openssl/evp.h>
#include <openssl/pem.h>
#include <openssl/pkcs7.h>
#include <openssl/x509.h>
#include <openssl/x509v3.h>
#include <sys/stat.h>
#include <unistd.h>

#include <cerrno>
#include <cstring>
#include <ctime>
#include <memory>
#include <stdexcept>
#include <system_error>

#include "concert/common/text.hpp"
#include "concert/security/table.hpp"

namespace concert::security {
namespace fs = std::filesystem;

namespace {

template <auto Free>
struct Deleter {
  template <class T>
  void operator()(T* p) const {
    Free(p);
  }
};
using Key = std::unique_ptr<EVP_PKEY, Deleter<EVP_PKEY_free>>;
using Cert = std::unique_ptr<X509, Deleter<X509_free>>;
using Name = std::unique_ptr<X509_NAME, Deleter<X509_NAME_free>>;
using Bio = std::unique_ptr<BIO, Deleter<BIO_free_all>>;
using Bignum = std::unique_ptr<BIGNUM, Deleter<BN_free>>;
using Pkcs7 = std::unique_ptr<PKCS7, Deleter<PKCS7_free>>;
using Store = std::unique_ptr<X509_STORE, Deleter<X509_STORE_free>>;
using StoreCtx = std::unique_ptr<X509_STORE_CTX, Deleter<X509_STORE_CTX_free>>;
using Extension = std::unique_ptr<X509_EXTENSION, Deleter<X509_EXTENSION_free>>;

constexpr int kMaxDays = 3650;
constexpr long kCertificateSlackS = 3600;  ///< certificates start an hour back (clock skew)
constexpr auto kPermissionsSlack = std::chrono::hours(24);  ///< XML times: any time zone

/// OpenSSL's error queue as text (and emptied).
std::string openssl_errors() {
  std::string text;
  while (const unsigned long e = ERR_get_error()) {
    char buf[256];
    ERR_error_string_n(e, buf, sizeof buf);
    if (!text.empty()) text += "; ";
    text += buf;
  }
  return text.empty() ? "no detail from OpenSSL" : text;
}

[[noreturn]] void fail(const std::string& what) {
  throw std::runtime_error(what + " (" + openssl_errors() + ")");
}

Key new_key() {
  Key key(EVP_PKEY_Q_keygen(nullptr, nullptr, "EC", "P-256"));
  if (!key) fail("cannot generate an EC P-256 key");
  return key;
}

/// O=CONCERT, CN=cn (in this order, so the RFC 2253 text is "CN=cn,O=CONCERT").
Name make_name(const std::string& cn) {
  Name name(X509_NAME_new());
  const auto add = [&](const char* field, const std::string& value) {
    if (X509_NAME_add_entry_by_txt(name.get(), field, MBSTRING_UTF8,
                                   reinterpret_cast<const unsigned char*>(value.c_str()), -1, -1,
                                   0) != 1) {
      fail("cannot build the subject name " + cn);
    }
  };
  add("O", "CONCERT");
  add("CN", cn);
  return name;
}

void add_extension(X509* cert, X509* issuer, int nid, const char* value) {
  X509V3_CTX ctx;
  X509V3_set_ctx_nodb(&ctx);
  X509V3_set_ctx(&ctx, issuer, cert, nullptr, nullptr, 0);
  Extension ext(X509V3_EXT_conf_nid(nullptr, &ctx, nid, value));
  if (!ext || X509_add_ext(cert, ext.get(), -1) != 1)
    fail(std::string("cannot add the extension ") + value);
}

/// A certificate for `key` named `cn`, signed by `issuer`/`issuer_key` (itself when null).
/// `alt_names` (an X.509v3 subjectAltName value, e.g. "DNS:localhost,IP:127.0.0.1") makes it a
/// TLS server certificate.
Cert make_certificate(const std::string& cn, EVP_PKEY* key, X509* issuer, EVP_PKEY* issuer_key,
                      int days, const std::string& alt_names = "") {
  Cert cert(X509_new());
  const bool ca = issuer == nullptr;
  Bignum serial(BN_new());
  if (!cert || !serial || X509_set_version(cert.get(), X509_VERSION_3) != 1 ||
      BN_rand(serial.get(), 127, BN_RAND_TOP_ANY, BN_RAND_BOTTOM_ANY) != 1 ||
      BN_to_ASN1_INTEGER(serial.get(), X509_get_serialNumber(cert.get())) == nullptr) {
    fail("cannot start the certificate of " + cn);
  }
  const Name subject = make_name(cn);
  if (X509_set_subject_name(cert.get(), subject.get()) != 1 ||
      X509_set_issuer_name(cert.get(), ca ? subject.get() : X509_get_subject_name(issuer)) != 1 ||
      X509_set_pubkey(cert.get(), key) != 1 ||
      X509_gmtime_adj(X509_getm_notBefore(cert.get()), -kCertificateSlackS) == nullptr ||
      X509_time_adj_ex(X509_getm_notAfter(cert.get()), days, 0, nullptr) == nullptr) {
    fail("cannot fill the certificate of " + cn);
  }
  X509* signer = ca ? cert.get() : issuer;
  add_extension(cert.get(), signer, NID_basic_constraints,
                ca ? "critical,CA:TRUE" : "critical,CA:FALSE");
  // The CA signs the governance and permissions documents too (S/MIME): digitalSignature.
  add_extension(cert.get(), signer, NID_key_usage,
                ca ? "critical,digitalSignature,keyCertSign,cRLSign"
                   : "critical,digitalSignature,keyAgreement");
  if (!alt_names.empty()) {
    add_extension(cert.get(), signer, NID_subject_alt_name, alt_names.c_str());
    add_extension(cert.get(), signer, NID_ext_key_usage, "serverAuth");
  }
  add_extension(cert.get(), signer, NID_subject_key_identifier, "hash");
  if (!ca) add_extension(cert.get(), signer, NID_authority_key_identifier, "keyid:always");
  if (X509_sign(cert.get(), ca ? key : issuer_key, EVP_sha256()) == 0)
    fail("cannot sign the certificate of " + cn);
  return cert;
}

std::string bio_text(BIO* bio) {
  char* data = nullptr;
  const long n = BIO_get_mem_data(bio, &data);
  return std::string(data, static_cast<size_t>(n));
}

std::string pem(X509* cert) {
  Bio out(BIO_new(BIO_s_mem()));
  if (PEM_write_bio_X509(out.get(), cert) != 1) fail("cannot write a certificate as PEM");
  return bio_text(out.get());
}

std::string pem(EVP_PKEY* key) {
  Bio out(BIO_new(BIO_s_mem()));
  if (PEM_write_bio_PrivateKey(out.get(), key, nullptr, nullptr, 0, nullptr, nullptr) != 1) {
    fail("cannot write a private key as PEM");
  }
  return bio_text(out.get());
}

/// `text` signed by the CA as S/MIME (detached, text mode): what `openssl smime -sign -text`
/// writes and what both DDS vendors verify.
std::string smime_sign(const std::string& text, X509* ca, EVP_PKEY* ca_key) {
  Bio in(BIO_new_mem_buf(text.data(), static_cast<int>(text.size())));
  const int flags = PKCS7_DETACHED | PKCS7_TEXT | PKCS7_STREAM;
  Pkcs7 p7(PKCS7_sign(ca, ca_key, nullptr, in.get(), flags));
  Bio out(BIO_new(BIO_s_mem()));
  if (!p7 || SMIME_write_PKCS7(out.get(), p7.get(), in.get(), flags) != 1)
    fail("cannot sign a document");
  return bio_text(out.get());
}

/// Writes `content` to `path` with `mode`, through a temporary file renamed over it: the file
/// never exists with another mode, and an old file is replaced whole.
void write_file(const fs::path& path, const std::string& content, mode_t mode) {
  const fs::path tmp = path.string() + ".tmp";
  ::unlink(tmp.c_str());
  const int fd = ::open(tmp.c_str(), O_WRONLY | O_CREAT | O_EXCL | O_CLOEXEC, mode);
  if (fd < 0)
    throw std::runtime_error("cannot create '" + tmp.string() + "': " + std::strerror(errno));
  size_t done = 0;
  while (done < content.size()) {
    const ssize_t n = ::write(fd, content.data() + done, content.size() - done);
    if (n < 0) {
      const int e = errno;
      ::close(fd);
      throw std::runtime_error("cannot write '" + tmp.string() + "': " + std::strerror(e));
    }
    done += static_cast<size_t>(n);
  }
  const bool moded = ::fchmod(fd, mode) == 0;  // whatever the umask took away
  const bool closed = ::close(fd) == 0;
  if (!moded || !closed || std::rename(tmp.c_str(), path.c_str()) != 0) {
    throw std::runtime_error("cannot write '" + path.string() + "': " + std::strerror(errno));
  }
}

void make_folder(const fs::path& dir) {
  std::error_code ec;
  fs::create_directories(dir, ec);
  if (ec || !fs::is_directory(dir)) {
    throw std::runtime_error("cannot create the folder '" + dir.string() +
                             "': " + (ec ? ec.message() : "a file of that name is in the way"));
  }
}

Bio open_file(const fs::path& path, const std::string& what) {
  Bio in(BIO_new_file(path.c_str(), "r"));
  if (!in) {
    ERR_clear_error();
    throw std::runtime_error(what + " '" + path.string() + "' cannot be read (" +
                             (fs::exists(path) ? "permission denied" : "missing") +
                             "; is it a folder made by `concert security init`?)");
  }
  return in;
}

Cert read_certificate(const fs::path& path, const std::string& what) {
  Bio in = open_file(path, what);
  Cert cert(PEM_read_bio_X509(in.get(), nullptr, nullptr, nullptr));
  if (!cert) {
    ERR_clear_error();
    throw std::runtime_error(what + " '" + path.string() + "' is not a PEM certificate");
  }
  return cert;
}

Key read_key(const fs::path& path, const std::string& what) {
  Bio in = open_file(path, what);
  Key key(PEM_read_bio_PrivateKey(in.get(), nullptr, nullptr, nullptr));
  if (!key) {
    ERR_clear_error();
    throw std::runtime_error(what + " '" + path.string() + "' is not a PEM private key");
  }
  return key;
}

/// "IP:a.b.c.d" for an address, "DNS:name" for a host name; refuses anything else.
std::string alt_name(const std::string& name) {
  unsigned char buf[16];
  if (::inet_pton(AF_INET, name.c_str(), buf) == 1 || ::inet_pton(AF_INET6, name.c_str(), buf) == 1) {
    return "IP:" + name;
  }
  const bool host = !name.empty() && name.size() <= 253 && name.front() != '-' && name.front() != '.' &&
                    std::all_of(name.begin(), name.end(), [](char c) {
                      return std::isalnum(static_cast<unsigned char>(c)) != 0 || c == '-' || c == '.';
                    });
  if (!host) throw std::invalid_argument("--name '" + name + "': neither a host name nor an IP address");
  return "DNS:" + name;
}

/// The RFC 2253 text of a certificate's subject ("CN=robot,O=CONCERT").
std::string subject_text(X509* cert) {
  Bio out(BIO_new(BIO_s_mem()));
  X509_NAME_print_ex(out.get(), X509_get_subject_name(cert), 0, XN_FLAG_RFC2253);
  return bio_text(out.get());
}

/// The content of a signed document, after checking its signature against `store`.
std::string verified_document(const fs::path& path, const std::string& what, X509_STORE* store,
                              const fs::path& ca) {
  Bio in = open_file(path, what);
  BIO* content = nullptr;
  Pkcs7 p7(SMIME_read_PKCS7(in.get(), &content));
  Bio content_owner(content);
  if (!p7) {
    ERR_clear_error();
    throw std::runtime_error(what + " '" + path.string() + "' is not an S/MIME signed document");
  }
  Bio out(BIO_new(BIO_s_mem()));
  if (PKCS7_verify(p7.get(), nullptr, store, content, out.get(), PKCS7_TEXT) != 1) {
    const std::string why = openssl_errors();
    throw std::runtime_error(what + " '" + path.string() +
                             "': the signature does not verify against '" + ca.string() +
                             "' (edited, or signed by another CA: " + why + ")");
  }
  return bio_text(out.get());
}

std::string tag_text(const std::string& xml, const std::string& tag) {
  const std::string open = "<" + tag + ">", close = "</" + tag + ">";
  const size_t a = xml.find(open);
  const size_t b = a == std::string::npos ? a : xml.find(close, a);
  if (b == std::string::npos) return {};
  return xml.substr(a + open.size(), b - a - open.size());
}

std::string format_time(const ASN1_TIME* t) {
  std::tm tm{};
  if (ASN1_TIME_to_tm(t, &tm) != 1) return "?";
  char text[40];
  std::strftime(text, sizeof text, "%Y-%m-%d %H:%M:%S UTC", &tm);
  return text;
}

}  // namespace

IdentityFiles identity_files(const fs::path& dir, std::string_view identity) {
  const fs::path own = dir / std::string(identity);
  return {std::string(identity), dir / "ca.pem",  dir / "governance.p7s",
          own / "cert.pem",      own / "key.pem", own / "permissions.p7s"};
}

std::vector<CreatedFile> init_pki(const fs::path& dir, const InitOptions& options) {
  if (options.days < 1 || options.days > kMaxDays) {
    throw std::invalid_argument("--days: " + std::to_string(options.days) +
                                " is not a validity from 1 to " + std::to_string(kMaxDays) +
                                " days");
  }
  // Everything init writes, checked before anything is written.
  std::vector<std::pair<fs::path, std::string>> plan = {
      {dir / "ca.pem", "CA certificate"},
      {dir / "ca_key.pem", "CA private key"},
      {dir / "governance.xml", "governance"},
      {dir / "governance.p7s", "governance, signed"}};
  for (const auto identity : identities()) {
    const std::string id(identity);
    const fs::path own = dir / id;
    plan.push_back({own / "cert.pem", "certificate of " + id});
    plan.push_back({own / "key.pem", "private key of " + id});
    plan.push_back({own / "permissions.xml", "permissions of " + id});
    plan.push_back({own / "permissions.p7s", "permissions of " + id + ", signed"});
  }
  if (!options.force) {
    for (const auto& [path, what] : plan) {
      std::error_code ec;
      if (fs::exists(path, ec)) {
        throw std::runtime_error("'" + dir.string() + "' already holds a PKI ('" + path.string() +
                                 "' exists): give --force to replace it (a new CA: every identity "
                                 "made before stops working)");
      }
    }
  }
  make_folder(dir);

  const auto now = std::chrono::system_clock::now();
  const Validity validity{now - kPermissionsSlack, now + std::chrono::hours(24) * options.days};
  std::vector<CreatedFile> created;
  size_t next = 0;
  const auto write = [&](const std::string& content, mode_t mode) {
    write_file(plan[next].first, content, mode);
    created.push_back({plan[next].first, plan[next].second});
    ++next;
  };

  const Key ca_key = new_key();
  const Cert ca = make_certificate("CONCERT CA", ca_key.get(), nullptr, nullptr, options.days);
  write(pem(ca.get()), 0644);
  write(pem(ca_key.get()), 0600);
  const std::string governance = governance_xml(options.governance);
  write(governance, 0644);
  write(smime_sign(governance, ca.get(), ca_key.get()), 0644);
  for (const auto identity : identities()) {
    const std::string id(identity);
    make_folder(dir / id);
    const Key key = new_key();
    const Cert cert = make_certificate(id, key.get(), ca.get(), ca_key.get(), options.days);
    write(pem(cert.get()), 0644);
    write(pem(key.get()), 0600);
    const std::string permissions = permissions_xml(identity, validity);
    write(permissions, 0644);
    write(smime_sign(permissions, ca.get(), ca_key.get()), 0644);
  }
  char host[256] = {};
  HttpsOptions https{{}, options.days};
  if (::gethostname(host, sizeof host - 1) == 0 && host[0] != '\0') https.names.emplace_back(host);
  for (auto& f : issue_https_certificate(dir, https)) created.push_back(std::move(f));
  return created;
}

std::vector<CreatedFile> issue_https_certificate(const fs::path& dir, const HttpsOptions& options) {
  if (options.days < 1 || options.days > kMaxDays) {
    throw std::invalid_argument("--days: " + std::to_string(options.days) + " is not a validity from 1 to " +
                                std::to_string(kMaxDays) + " days");
  }
  std::vector<std::string> names = {"localhost", "127.0.0.1", "::1"};
  for (const auto& n : options.names) {
    if (std::find(names.begin(), names.end(), n) == names.end()) names.push_back(n);
  }
  std::string alt;
  for (const auto& n : names) alt += (alt.empty() ? "" : ",") + alt_name(n);
  const Cert ca = read_certificate(dir / "ca.pem", "CA certificate");
  const Key ca_key = read_key(dir / "ca_key.pem", "CA private key");
  make_folder(dir / "gui");
  const Key key = new_key();
  const Cert cert = make_certificate("CONCERT operator GUI", key.get(), ca.get(), ca_key.get(), options.days, alt);
  const fs::path cert_file = dir / "gui" / "https_cert.pem";
  const fs::path key_file = dir / "gui" / "https_key.pem";
  // The key first: a certificate is never on disk without the key that goes with it.
  write_file(key_file, pem(key.get()), 0600);
  write_file(cert_file, pem(cert.get()) + pem(ca.get()), 0644);
  return {{key_file, "private key of the GUI's HTTPS certificate"},
          {cert_file, "HTTPS certificate of the GUI (" + alt + ")"}};
}

void check_identity(const IdentityFiles& f) {
  const Cert ca = read_certificate(f.ca, "CA certificate");
  const Cert cert = read_certificate(f.certificate, "certificate of " + f.identity);
  Store store(X509_STORE_new());
  if (!store || X509_STORE_add_cert(store.get(), ca.get()) != 1)
    fail("cannot load the CA certificate");

  StoreCtx ctx(X509_STORE_CTX_new());
  if (!ctx || X509_STORE_CTX_init(ctx.get(), store.get(), cert.get(), nullptr) != 1) {
    fail("cannot check a certificate");
  }
  if (X509_verify_cert(ctx.get()) != 1) {
    const int e = X509_STORE_CTX_get_error(ctx.get());
    ERR_clear_error();
    throw std::runtime_error("certificate of " + f.identity + " '" + f.certificate.string() +
                             "': " + X509_verify_cert_error_string(e) + " (checked against '" +
                             f.ca.string() + "', valid until " +
                             format_time(X509_get0_notAfter(cert.get())) + ")");
  }
  {
    Bio in = open_file(f.private_key, "private key of " + f.identity);
    Key key(PEM_read_bio_PrivateKey(in.get(), nullptr, nullptr, nullptr));
    if (!key || X509_check_private_key(cert.get(), key.get()) != 1) {
      ERR_clear_error();
      throw std::runtime_error("private key of " + f.identity + " '" + f.private_key.string() +
                               "' does not belong to its certificate '" + f.certificate.string() +
                               "'");
    }
  }
  verified_document(f.governance, "governance", store.get(), f.ca);
  const std::string permissions =
      verified_document(f.permissions, "permissions of " + f.identity, store.get(), f.ca);
  const std::string granted = tag_text(permissions, "subject_name");
  const std::string subject = subject_text(cert.get());
  if (granted != subject) {
    throw std::runtime_error("permissions of " + f.identity + " '" + f.permissions.string() +
                             "' are granted to '" + granted +
                             "', not to the certificate's subject '" + subject + "'");
  }
}

std::string certificate_expiry(const fs::path& certificate) {
  const Cert cert = read_certificate(certificate, "certificate");
  return format_time(X509_get0_notAfter(cert.get()));
}

std::vector<unsigned char> subject_hash(const fs::path& certificate) {
  const Cert cert = read_certificate(certificate, "certificate");
  unsigned char* der = nullptr;
  const int n = i2d_X509_NAME(X509_get_subject_name(cert.get()), &der);
  if (n <= 0) fail("cannot encode a subject name");
  std::vector<unsigned char> hash(EVP_MAX_MD_SIZE);
  unsigned int size = 0;
  const int ok = EVP_Digest(der, static_cast<size_t>(n), hash.data(), &size, EVP_sha256(), nullptr);
  OPENSSL_free(der);
  if (ok != 1) fail("cannot hash a subject name");
  hash.resize(size);
  return hash;
}

}  // namespace concert::security
