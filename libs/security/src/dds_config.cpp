#include "concert/security/dds_config.hpp"

#include <cstdlib>
#include <stdexcept>

#include "concert/common/text.hpp"
#include "concert/security/table.hpp"

namespace concert::security {
namespace {

std::string checked(std::string_view identity, std::string_view source) {
  if (!is_identity(identity)) {
    const auto& all = identities();
    throw std::invalid_argument(std::string(source) + ": '" + std::string(identity) +
                                "' is not an identity (one of " + join(all, ", ") + ")");
  }
  return std::string(identity);
}

std::string absolute_path(const std::filesystem::path& p) {
  return std::filesystem::absolute(p).lexically_normal().string();
}

}  // namespace

std::optional<std::filesystem::path> pki_from_environment() {
  const char* dir = std::getenv("CONCERT_SECURITY");
  if (dir == nullptr || *dir == '\0') return std::nullopt;
  return std::filesystem::path(dir);
}

std::string resolve_identity(std::string_view explicit_identity,
                             std::string_view participant_name) {
  if (!explicit_identity.empty()) return checked(explicit_identity, "security identity");
  if (is_service_identity(participant_name)) return std::string(participant_name);
  if (const char* env = std::getenv("CONCERT_SECURITY_IDENTITY"); env != nullptr && *env != '\0') {
    return checked(env, "CONCERT_SECURITY_IDENTITY");
  }
  return std::string(kOperator);
}

std::vector<std::pair<std::string, std::string>> fastdds_properties(const IdentityFiles& f) {
  const auto uri = [](const std::filesystem::path& p) { return "file://" + absolute_path(p); };
  const std::string auth = "dds.sec.auth.builtin.PKI-DH.";
  const std::string access = "dds.sec.access.builtin.Access-Permissions.";
  return {
      {"dds.sec.auth.plugin", "builtin.PKI-DH"},
      {auth + "identity_ca", uri(f.ca)},
      {auth + "identity_certificate", uri(f.certificate)},
      {auth + "private_key", uri(f.private_key)},
      {"dds.sec.access.plugin", "builtin.Access-Permissions"},
      {access + "permissions_ca", uri(f.ca)},
      {access + "governance", uri(f.governance)},
      {access + "permissions", uri(f.permissions)},
      {"dds.sec.crypto.plugin", "builtin.AES-GCM-GMAC"},
  };
}

std::string cyclone_security_config(const IdentityFiles& f,
                                    const std::filesystem::path& plugin_dir) {
  // Cyclone takes "file:" + an absolute path (no "//").
  const auto uri = [](const std::filesystem::path& p) { return "file:" + absolute_path(p); };
  const auto library = [&plugin_dir](const char* name, const char* init, const char* fini) {
    return "<Library path=\"" + (plugin_dir / name).string() + "\" initFunction=\"" + init +
           "\" finalizeFunction=\"" + fini + "\"/>";
  };
  return "<CycloneDDS><Domain Id=\"any\"><Security>"
         "<Authentication>" +
         library("libdds_security_auth.so", "init_authentication", "finalize_authentication") +
         "<IdentityCA>" + uri(f.ca) + "</IdentityCA>" + "<IdentityCertificate>" +
         uri(f.certificate) + "</IdentityCertificate>" + "<PrivateKey>" + uri(f.private_key) +
         "</PrivateKey>" +
         "</Authentication>"
         "<AccessControl>" +
         library("libdds_security_ac.so", "init_access_control", "finalize_access_control") +
         "<PermissionsCA>" + uri(f.ca) + "</PermissionsCA>" + "<Governance>" + uri(f.governance) +
         "</Governance>" + "<Permissions>" + uri(f.permissions) + "</Permissions>" +
         "</AccessControl>"
         "<Cryptographic>" +
         library("libdds_security_crypto.so", "init_crypto", "finalize_crypto") +
         "</Cryptographic>"
         "</Security></Domain></CycloneDDS>";
}

}  // namespace concert::security
