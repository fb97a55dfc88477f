#pragma once
// How a process runs secured: CONCERT_SECURITY=DIR (a folder made by `concert security init`)
// turns security on for every participant; each participant picks its identity (below), and the
// vendors' builtin plugins are configured from that identity's files. Plain strings, no DDS
// includes: libs/dds applies them to Fast DDS, the Cyclone test peers to Cyclone.

#include <filesystem>
#include <optional>
#include <string>
#include <string_view>
#include <utility>
#include <vector>

#include "concert/security/pki.hpp"

namespace concert::security {

/// The PKI folder CONCERT_SECURITY names (nullopt when unset or empty: security off).
std::optional<std::filesystem::path> pki_from_environment();

/// The identity a participant uses: `explicit_identity` when given; else the participant's
/// name when it is a service identity (a service's participant is named after it, e.g.
/// "robot"); else CONCERT_SECURITY_IDENTITY when set; else "operator" (the tools). Throws
/// std::invalid_argument naming the source when the result is no identity of the table.
std::string resolve_identity(std::string_view explicit_identity, std::string_view participant_name);

/// Fast DDS participant properties (name, value) for the builtin PKI-DH, Access-Permissions and
/// AES-GCM-GMAC plugins with `files`.
std::vector<std::pair<std::string, std::string>> fastdds_properties(const IdentityFiles& files);

/// A Cyclone DDS configuration fragment (<CycloneDDS><Domain><Security>...) with `files`, for a
/// config string "BASE,FRAGMENT". `plugin_dir` holds libdds_security_{auth,ac,crypto}.so (Debian
/// puts them in a private folder, /usr/lib/<arch>/libddsc0debian, that dlopen does not search).
std::string cyclone_security_config(const IdentityFiles& files,
                                    const std::filesystem::path& plugin_dir);

}  // namespace concert::security
