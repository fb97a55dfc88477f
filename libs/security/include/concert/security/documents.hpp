#pragma once
// The DDS Security documents (OMG DDS Security 1.1, section 9.4) as text: the domain governance
// and one permissions document per identity, generated from the table (table.hpp). Signing them
// is pki.hpp's job. Both Fast DDS 2.9 and Cyclone DDS 0.10 read these documents.

#include <chrono>
#include <string>
#include <string_view>

namespace concert::security {

/// Domain ids the documents cover. Cyclone DDS 0.10 refuses a governance that names a domain
/// above 230, so 231 and 232 (valid DDS ids) are left out: a secured stack runs on 0..230.
inline constexpr int kFirstDomain = 0;
inline constexpr int kLastDomain = 230;

/// How a part of the traffic is protected (the standard's ProtectionKind).
enum class Protection { kNone, kSign, kEncrypt };

/// The governance's choices. The defaults are the stack's: what `concert security init` writes.
struct GovernanceOptions {
  /// Every RTPS message is encrypted and authenticated (AES-GCM) with the sending participant's
  /// key, which only authenticated participants get: nothing from outside is accepted, not even
  /// a forged heartbeat, and nothing inside can be read from outside.
  Protection rtps = Protection::kEncrypt;
  /// Discovery (endpoints, topic names, QoS) and liveliness are encrypted.
  Protection discovery = Protection::kEncrypt;
  Protection liveliness = Protection::kEncrypt;
  /// No second, per-writer protection of each topic's submessages: its keys go to the matched
  /// readers only, which protects nothing more while every identity may read every topic, and
  /// doubles the cost (bench_dds: README).
  Protection metadata = Protection::kNone;
  /// No payload protection either: Cyclone DDS 0.10 cannot decode Fast DDS 2.9's protected
  /// payloads (measured: with SIGN or ENCRYPT here no sample crosses Fast DDS -> Cyclone).
  Protection data = Protection::kNone;
};
/// The governance document: unauthenticated participants not allowed, join access control,
/// discovery and liveliness protected, read and write access control on every topic.
std::string governance_xml(const GovernanceOptions& options = {});

/// The subject name of `identity`'s certificate, as RFC 4514 (RFC 2253) text, the form both
/// DDS vendors compare a permissions grant against: "CN=robot,O=CONCERT".
std::string subject_name(std::string_view identity);

/// Validity of certificates and permissions.
struct Validity {
  std::chrono::system_clock::time_point not_before;
  std::chrono::system_clock::time_point not_after;
};

/// The permissions document of `identity`: publish exactly the topics the table gives it,
/// subscribe to every topic, deny everything else; valid in `validity`, on kFirstDomain..
/// kLastDomain. Throws std::invalid_argument for a name that is no identity.
std::string permissions_xml(std::string_view identity, const Validity& validity);

/// "2026-11-26T11:28:15" (UTC), the date-time form of the permissions' validity.
std::string xml_time(std::chrono::system_clock::time_point t);

}  // namespace concert::security
