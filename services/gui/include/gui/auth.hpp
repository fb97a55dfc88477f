#pragma once
// Who may use the operator GUI: users and roles kept on the robot, password sign-in (argon2id
// hashes from libsodium), one-time pairing codes, sessions that expire, and sign-in attempts
// slowed per address. No DDS and no sockets: the hub asks, the gateway's main keeps one.
//
// Roles, each including the ones before it:
//   viewer    sees everything, commands nothing but the e-stop
//   operator  missions, transport, navigation, safety reset
//   engineer  hot swap, homing, add-ons
// The e-stop is accepted from every signed-in client, whatever its role.

#include <cstdint>
#include <filesystem>
#include <map>
#include <mutex>
#include <optional>
#include <stdexcept>
#include <string>
#include <string_view>
#include <vector>

namespace concert::gui {

enum class Role { kViewer = 0, kOperator = 1, kEngineer = 2 };

std::string_view to_string(Role role);
/// "viewer", "operator" or "engineer"; nullopt otherwise.
std::optional<Role> role_from_string(std::string_view text);

/// A user file that cannot be read or written, or a user that cannot be added; the message
/// names the file or the field and what is wrong.
class UserError : public std::runtime_error {
 public:
  using std::runtime_error::runtime_error;
};

struct User {
  std::string name;
  Role role = Role::kViewer;
  std::string hash;  ///< libsodium's argon2id string ("$argon2id$v=19$m=...")
};

/// What a password hash costs to make and to check.
enum class HashCost {
  kInteractive,  ///< libsodium's interactive limits (64 MiB, 2 passes): every real user
  kMinimal,      ///< the least argon2id allows: for fuzzing the sign-in path only
};

/// The users of one robot: a JSON file written 0600 ({"users": [{"name", "role", "hash"}]}).
class UserStore {
 public:
  explicit UserStore(HashCost cost = HashCost::kInteractive) : cost_(cost) {}

  /// The file's users; an absent file is an empty store. Throws UserError naming the file and
  /// the entry for anything else it cannot use (not JSON, a role that does not exist, a hash
  /// that is not argon2id).
  static UserStore load(const std::filesystem::path& file);
  /// Writes the store atomically (a temporary file renamed over it), mode 0600.
  void save(const std::filesystem::path& file) const;

  /// Adds or replaces `name`. Names: 1-32 of [A-Za-z0-9._-]; passwords at least 8 characters.
  void add(const std::string& name, Role role, const std::string& password);
  bool remove(const std::string& name);
  const std::vector<User>& users() const { return users_; }
  /// The user's role when `password` is theirs. Costs one argon2id verification whether or not
  /// the user exists (a wrong name is not answered faster than a wrong password).
  std::optional<Role> verify(const std::string& name, const std::string& password) const;

 private:
  HashCost cost_;
  std::vector<User> users_;
  mutable std::string dummy_;  ///< a hash of nobody's password, checked for unknown names
};

struct AuthParams {
  int64_t session_ttl_s = 12 * 3600;  ///< a session ends this long after sign-in [s]
  int free_attempts = 5;              ///< wrong sign-ins from one address before slowing it
  double first_delay_s = 1.0;         ///< the wait after the first slowed attempt [s]
  double max_delay_s = 60.0;          ///< the wait doubles per wrong attempt up to this [s]
  Role pairing_role = Role::kOperator;  ///< the role a pairing code grants
  int64_t pairing_ttl_s = 600;          ///< a pairing code expires this long after it is made [s]
};

struct Session {
  std::string token;  ///< 64 hex digits, random (libsodium)
  std::string user;
  Role role = Role::kViewer;
  int64_t expires_ns = 0;
};

/// A sign-in refused: why, and when the address may try again (0: now).
class SignInRefused : public std::runtime_error {
 public:
  SignInRefused(const std::string& why, double retry_after)
      : std::runtime_error(why), retry_after_s(retry_after) {}
  double retry_after_s;
};

/// Sessions and sign-in. Thread-safe. Times are the caller's clock [ns].
class Auth {
 public:
  Auth(UserStore users, AuthParams params);

  /// A session for `user` when `password` is right. `address` is the client's IP (no port):
  /// after `free_attempts` wrong ones from it, each further attempt within the delay is refused
  /// unchecked (SignInRefused with retry_after_s), the delay doubling per wrong attempt.
  Session sign_in(const std::string& address, const std::string& user, const std::string& password, int64_t now_ns);
  /// The session `token` names, when it has not expired (a reloaded page signs in with it).
  Session resume(const std::string& address, const std::string& token, int64_t now_ns);
  /// A session for a pairing code made by new_pairing_code(); each code works once.
  Session pair(const std::string& address, const std::string& code, int64_t now_ns);
  void sign_out(const std::string& token);
  /// The session of `token` when valid now.
  std::optional<Session> session(const std::string& token, int64_t now_ns) const;

  /// A new one-time pairing code (8 digits, random), replacing any unused one.
  std::string new_pairing_code(int64_t now_ns);
  /// Whether an unused, unexpired pairing code exists.
  bool pairing_open(int64_t now_ns) const;

  const AuthParams& params() const { return params_; }
  size_t user_count() const;

 private:
  struct Attempts {
    int wrong = 0;
    int64_t not_before_ns = 0;
  };
  void check_allowed_locked(const std::string& address, int64_t now_ns);
  [[noreturn]] void wrong_locked(const std::string& address, const std::string& why, int64_t now_ns);
  Session open_locked(const std::string& user, Role role, int64_t now_ns);

  UserStore users_;
  AuthParams params_;
  mutable std::mutex mutex_;
  std::map<std::string, Session> sessions_;  // by token
  std::map<std::string, Attempts> attempts_;  // by address
  std::string pairing_code_;
  int64_t pairing_expires_ns_ = 0;
};

/// The address part of "ADDR:PORT" or "[V6]:PORT" (rate limits are per address, not per socket).
std::string address_of(std::string_view origin);

}  // namespace concert::gui
