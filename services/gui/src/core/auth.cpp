#include "gui/auth.hpp"

#include <fcntl.h>
#include <sodium.h>
#include <sys/stat.h>
#include <unistd.h>

#include <algorithm>
#include <cmath>
#include <cstring>
#include <fstream>
#include <nlohmann/json.hpp>
#include <sstream>

namespace concert::gui {

namespace fs = std::filesystem;

namespace {

void init_sodium() {
  if (sodium_init() < 0) throw std::runtime_error("libsodium cannot start (sodium_init failed)");
}

std::string hash_password(const std::string& password, HashCost cost) {
  init_sodium();
  char out[crypto_pwhash_STRBYTES];
  // Argon2id with libsodium's interactive limits (64 MiB, 2 passes): a sign-in costs about a
  // tenth of a second here, and a stolen user file costs an attacker as much per guess.
  const bool real = cost == HashCost::kInteractive;
  if (crypto_pwhash_str_alg(out, password.data(), password.size(),
                            real ? crypto_pwhash_OPSLIMIT_INTERACTIVE : crypto_pwhash_OPSLIMIT_MIN,
                            real ? crypto_pwhash_MEMLIMIT_INTERACTIVE : crypto_pwhash_MEMLIMIT_MIN,
                            crypto_pwhash_ALG_ARGON2ID13) != 0) {
    throw UserError("cannot hash the password (out of memory for argon2id)");
  }
  return out;
}

bool valid_name(const std::string& name) {
  if (name.empty() || name.size() > 32) return false;
  return std::all_of(name.begin(), name.end(), [](char c) {
    return (c >= 'a' && c <= 'z') || (c >= 'A' && c <= 'Z') || (c >= '0' && c <= '9') || c == '.' || c == '_' ||
           c == '-';
  });
}

std::string random_hex(size_t bytes) {
  init_sodium();
  std::vector<unsigned char> raw(bytes);
  randombytes_buf(raw.data(), raw.size());
  std::string hex(bytes * 2 + 1, '\0');
  sodium_bin2hex(hex.data(), hex.size(), raw.data(), raw.size());
  hex.pop_back();
  return hex;
}

/// Constant-time comparison of two strings of the same length (tokens, pairing codes).
bool same(const std::string& a, const std::string& b) {
  return a.size() == b.size() && sodium_memcmp(a.data(), b.data(), a.size()) == 0;
}

}  // namespace

std::string_view to_string(Role role) {
  switch (role) {
    case Role::kViewer: return "viewer";
    case Role::kOperator: return "operator";
    case Role::kEngineer: return "engineer";
  }
  return "?";
}

std::optional<Role> role_from_string(std::string_view text) {
  for (Role r : {Role::kViewer, Role::kOperator, Role::kEngineer}) {
    if (to_string(r) == text) return r;
  }
  return std::nullopt;
}

UserStore UserStore::load(const fs::path& file) {
  UserStore store;
  std::error_code ec;
  if (!fs::exists(file, ec)) return store;
  std::ifstream in(file);
  if (!in) throw UserError("user file '" + file.string() + "' cannot be read");
  nlohmann::json j;
  try {
    j = nlohmann::json::parse(in);
  } catch (const nlohmann::json::exception& e) {
    throw UserError("user file '" + file.string() + "' is not JSON: " + e.what());
  }
  if (!j.is_object() || !j.contains("users") || !j["users"].is_array()) {
    throw UserError("user file '" + file.string() + "': expected {\"users\": [...]}");
  }
  size_t index = 0;
  for (const auto& u : j["users"]) {
    const std::string where = "user file '" + file.string() + "', users[" + std::to_string(index++) + "]";
    if (!u.is_object() || !u.contains("name") || !u["name"].is_string() || !u.contains("role") ||
        !u["role"].is_string() || !u.contains("hash") || !u["hash"].is_string()) {
      throw UserError(where + ": needs string fields name, role and hash");
    }
    User user{u["name"].get<std::string>(), Role::kViewer, u["hash"].get<std::string>()};
    if (!valid_name(user.name)) throw UserError(where + ": name '" + user.name + "' is not 1-32 of [A-Za-z0-9._-]");
    const auto role = role_from_string(u["role"].get<std::string>());
    if (!role) throw UserError(where + ": role '" + u["role"].get<std::string>() + "' (viewer, operator, engineer)");
    user.role = *role;
    if (user.hash.rfind("$argon2id$", 0) != 0 || user.hash.size() >= crypto_pwhash_STRBYTES) {
      throw UserError(where + ": hash of '" + user.name + "' is not an argon2id string");
    }
    store.users_.push_back(std::move(user));
  }
  return store;
}

void UserStore::save(const fs::path& file) const {
  nlohmann::json list = nlohmann::json::array();
  for (const auto& u : users_) list.push_back({{"name", u.name}, {"role", to_string(u.role)}, {"hash", u.hash}});
  const std::string text = nlohmann::json{{"users", list}}.dump(2) + "\n";
  if (file.has_parent_path()) {
    std::error_code ec;
    fs::create_directories(file.parent_path(), ec);
    if (ec) throw UserError("cannot make the folder of '" + file.string() + "': " + ec.message());
  }
  const fs::path tmp = file.string() + ".tmp";
  // Created 0600 from the start: the hashes are never readable by others, not even briefly.
  const int fd = ::open(tmp.c_str(), O_WRONLY | O_CREAT | O_TRUNC | O_CLOEXEC, 0600);
  if (fd < 0) throw UserError("cannot write '" + tmp.string() + "': " + std::strerror(errno));
  const bool written = ::write(fd, text.data(), text.size()) == static_cast<ssize_t>(text.size());
  const bool closed = ::fsync(fd) == 0 && ::close(fd) == 0;
  if (!written || !closed) {
    ::unlink(tmp.c_str());
    throw UserError("cannot write '" + tmp.string() + "'");
  }
  if (::rename(tmp.c_str(), file.c_str()) != 0) {
    ::unlink(tmp.c_str());
    throw UserError("cannot replace '" + file.string() + "': " + std::strerror(errno));
  }
}

void UserStore::add(const std::string& name, Role role, const std::string& password) {
  if (!valid_name(name)) throw UserError("user name '" + name + "': 1-32 of [A-Za-z0-9._-]");
  if (password.size() < 8) throw UserError("password of '" + name + "': at least 8 characters");
  User user{name, role, hash_password(password, cost_)};
  auto it = std::find_if(users_.begin(), users_.end(), [&](const User& u) { return u.name == name; });
  if (it != users_.end()) {
    *it = std::move(user);
  } else {
    users_.push_back(std::move(user));
  }
}

bool UserStore::remove(const std::string& name) {
  const auto before = users_.size();
  users_.erase(std::remove_if(users_.begin(), users_.end(), [&](const User& u) { return u.name == name; }),
               users_.end());
  return users_.size() != before;
}

std::optional<Role> UserStore::verify(const std::string& name, const std::string& password) const {
  init_sodium();
  auto it = std::find_if(users_.begin(), users_.end(), [&](const User& u) { return u.name == name; });
  if (it == users_.end()) {
    // The same work for a name that does not exist: a dummy hash made once.
    if (dummy_.empty()) dummy_ = hash_password("not a password of anyone", cost_);
    const int same_work = crypto_pwhash_str_verify(dummy_.c_str(), password.data(), password.size());
    static_cast<void>(same_work);
    return std::nullopt;
  }
  if (crypto_pwhash_str_verify(it->hash.c_str(), password.data(), password.size()) != 0) return std::nullopt;
  return it->role;
}

Auth::Auth(UserStore users, AuthParams params) : users_(std::move(users)), params_(params) { init_sodium(); }

size_t Auth::user_count() const {
  std::lock_guard lock(mutex_);
  return users_.users().size();
}

void Auth::check_allowed_locked(const std::string& address, int64_t now_ns) {
  auto it = attempts_.find(address);
  if (it == attempts_.end() || now_ns >= it->second.not_before_ns) return;
  const double wait = std::ceil(static_cast<double>(it->second.not_before_ns - now_ns) * 1e-9);
  throw SignInRefused("too many failed sign-ins from " + address + ": try again in " +
                          std::to_string(static_cast<int>(wait)) + " s",
                      wait);
}

void Auth::wrong_locked(const std::string& address, const std::string& why, int64_t now_ns) {
  Attempts& a = attempts_[address];
  ++a.wrong;
  double delay = 0.0;
  if (a.wrong >= params_.free_attempts) {
    delay = std::min(params_.max_delay_s,
                     params_.first_delay_s * std::pow(2.0, static_cast<double>(a.wrong - params_.free_attempts)));
    a.not_before_ns = now_ns + static_cast<int64_t>(delay * 1e9);
  }
  // Bound the table: an address is forgotten once its wait is over and it has not failed for a
  // while; a flood of addresses cannot grow it beyond this.
  if (attempts_.size() > 4096) {
    for (auto i = attempts_.begin(); i != attempts_.end();) {
      i = i->second.not_before_ns < now_ns ? attempts_.erase(i) : std::next(i);
    }
  }
  throw SignInRefused(why, delay);
}

Session Auth::open_locked(const std::string& user, Role role, int64_t now_ns) {
  for (auto i = sessions_.begin(); i != sessions_.end();) {
    i = i->second.expires_ns <= now_ns ? sessions_.erase(i) : std::next(i);
  }
  Session s{random_hex(32), user, role, now_ns + params_.session_ttl_s * 1'000'000'000};
  sessions_[s.token] = s;
  return s;
}

Session Auth::sign_in(const std::string& address, const std::string& user, const std::string& password,
                      int64_t now_ns) {
  std::lock_guard lock(mutex_);
  check_allowed_locked(address, now_ns);
  const auto role = users_.verify(user, password);
  if (!role) wrong_locked(address, "sign-in refused: unknown user or wrong password", now_ns);
  attempts_.erase(address);
  return open_locked(user, *role, now_ns);
}

Session Auth::resume(const std::string& address, const std::string& token, int64_t now_ns) {
  std::lock_guard lock(mutex_);
  check_allowed_locked(address, now_ns);
  for (const auto& [t, s] : sessions_) {
    if (same(t, token) && s.expires_ns > now_ns) return s;
  }
  wrong_locked(address, "session expired or unknown: sign in again", now_ns);
}

Session Auth::pair(const std::string& address, const std::string& code, int64_t now_ns) {
  std::lock_guard lock(mutex_);
  check_allowed_locked(address, now_ns);
  if (pairing_code_.empty() || now_ns >= pairing_expires_ns_ || !same(code, pairing_code_)) {
    wrong_locked(address, "pairing refused: wrong or expired code", now_ns);
  }
  pairing_code_.clear();  // once
  attempts_.erase(address);
  return open_locked("paired@" + address, params_.pairing_role, now_ns);
}

void Auth::sign_out(const std::string& token) {
  std::lock_guard lock(mutex_);
  sessions_.erase(token);
}

std::optional<Session> Auth::session(const std::string& token, int64_t now_ns) const {
  std::lock_guard lock(mutex_);
  auto it = sessions_.find(token);
  if (it == sessions_.end() || it->second.expires_ns <= now_ns) return std::nullopt;
  return it->second;
}

std::string Auth::new_pairing_code(int64_t now_ns) {
  std::lock_guard lock(mutex_);
  // 8 decimal digits, uniform (randombytes_uniform has no modulo bias).
  std::string code;
  for (int i = 0; i < 8; ++i) code += static_cast<char>('0' + randombytes_uniform(10));
  pairing_code_ = code;
  pairing_expires_ns_ = now_ns + params_.pairing_ttl_s * 1'000'000'000;
  return code;
}

bool Auth::pairing_open(int64_t now_ns) const {
  std::lock_guard lock(mutex_);
  return !pairing_code_.empty() && now_ns < pairing_expires_ns_;
}

std::string address_of(std::string_view origin) {
  // websocketpp's remote endpoint: "1.2.3.4:5678" or "[::1]:5678".
  if (!origin.empty() && origin.front() == '[') {
    const auto close = origin.find(']');
    return std::string(origin.substr(1, close == std::string_view::npos ? std::string_view::npos : close - 1));
  }
  const auto colon = origin.rfind(':');
  return std::string(colon == std::string_view::npos ? origin : origin.substr(0, colon));
}

}  // namespace concert::gui
