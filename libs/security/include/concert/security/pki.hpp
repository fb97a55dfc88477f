#pragma once
// The stack's public-key infrastructure in one folder, and the files a participant reads from it.
//
//   DIR/ca.pem, DIR/ca_key.pem        the CA (identity CA and permissions CA in one), its key
//   DIR/governance.xml, .p7s          the domain governance, plain and signed by the CA
//   DIR/<identity>/cert.pem, key.pem  the identity's certificate (signed by the CA) and key
//   DIR/<identity>/permissions.xml, .p7s   what it may publish, plain and signed
//
// Keys are EC P-256 (ECDSA-SHA256 signatures, what both DDS vendors accept), written 0600 in
// folders made 0700. Made with libcrypto (OpenSSL 3) rather than by running the `openssl`
// command: errors come back as values naming the step, files are created with their final mode
// (no window where a key is readable), and nothing depends on a program on PATH. The `openssl`
// command checks the result in the tests, as an independent reader.

#include <filesystem>
#include <optional>
#include <string>
#include <string_view>
#include <vector>

#include "concert/security/documents.hpp"

namespace concert::security {

struct InitOptions {
  int days = 365;      ///< validity of the CA, the certificates and the permissions [days]
  bool force = false;  ///< replace an existing PKI (a new CA: every old identity stops working)
  GovernanceOptions governance;
};

/// One file written by init_pki().
struct CreatedFile {
  std::filesystem::path path;
  std::string what;  ///< e.g. "certificate of robot"
};

/// Creates the PKI in `dir` (made if missing): the CA, one identity per entry of identities(),
/// the signed governance and permissions, and the GUI's HTTPS certificate for this host
/// (issue_https_certificate with the host's name). Refuses (std::runtime_error naming the file) when
/// `dir` already holds a PKI and `force` is not set, and rejects days outside 1..3650
/// (std::invalid_argument). Returns what it wrote, in order.
std::vector<CreatedFile> init_pki(const std::filesystem::path& dir,
                                  const InitOptions& options = {});

/// What issue_https_certificate() makes.
struct HttpsOptions {
  /// Host names and IP addresses the operator GUI is reached at (subjectAltName); localhost,
  /// 127.0.0.1 and ::1 are always added.
  std::vector<std::string> names;
  int days = 365;
};

/// A TLS server certificate for the operator GUI's gateway (concert gui --tls DIR), signed by
/// the CA of `dir`: DIR/gui/https_cert.pem (the certificate, then the CA's) and
/// DIR/gui/https_key.pem (0600). Replaces an older one. Throws std::runtime_error naming the
/// file when the CA cannot be read, std::invalid_argument for a name that is neither a host
/// name nor an IP address.
std::vector<CreatedFile> issue_https_certificate(const std::filesystem::path& dir, const HttpsOptions& options);

/// The files one identity of a PKI folder uses.
struct IdentityFiles {
  std::string identity;
  std::filesystem::path ca;          ///< identity CA and permissions CA
  std::filesystem::path governance;  ///< signed
  std::filesystem::path certificate;
  std::filesystem::path private_key;
  std::filesystem::path permissions;  ///< signed
};

/// Where `identity`'s files are in `dir` (nothing is read).
IdentityFiles identity_files(const std::filesystem::path& dir, std::string_view identity);

/// Checks what a DDS security plugin would check, with a reason it would not give: every file
/// readable, the certificate signed by the CA and valid now, the governance and permissions
/// signed by the CA, the permissions granted to the certificate's subject. Throws
/// std::runtime_error naming the file and what is wrong.
void check_identity(const IdentityFiles& files);

/// The end of the certificate's validity, as "2027-11-26 11:28:15 UTC".
std::string certificate_expiry(const std::filesystem::path& certificate);

/// The DER subject name of a certificate, SHA-256 hashed: the first 47 bits of the hash are the
/// first bits of a secured participant's GUID (DDS Security 9.3.3), which decides which side
/// starts the authentication handshake (the lower GUID). Used to explain vendor interoperability.
std::vector<unsigned char> subject_hash(const std::filesystem::path& certificate);

}  // namespace concert::security
