#include "server/service/token_auth.h"

#include <string_view>

namespace vpm::service {
namespace {

// Equal-length strings compared without an early exit.
bool ConstantTimeEquals(std::string_view a, std::string_view b) {
  unsigned char diff = a.size() == b.size() ? 0 : 1;
  for (size_t i = 0; i < a.size(); ++i) {
    diff |= static_cast<unsigned char>(a[i] ^ (i < b.size() ? b[i] : 0));
  }
  return diff == 0;
}

}  // namespace

Result<TokenAuth> TokenAuth::Create(const Options& options) {
  TokenAuth auth;
  if (options.disabled) {
    if (!options.users.empty()) {
      return absl::InvalidArgumentError("--no-auth and --users contradict each other; give one");
    }
    auth.disabled_ = true;
    auth.users_.push_back({kNoAuthUser, ""});
    return auth;
  }
  auth.users_ = options.users;
  if (!options.token.empty()) {
    const std::string hash = HashToken(options.token);
    for (const UserCredential& user : auth.users_) {
      if (user.name == kDefaultTokenUser) {
        return absl::InvalidArgumentError(
            StrCat("--users names a user '", kDefaultTokenUser,
                   "', which is the --token user; rename it or drop --token"));
      }
      if (user.token_sha256_hex == hash) {
        return absl::InvalidArgumentError(
            StrCat("--token is the token of user '", user.name, "' of --users"));
      }
    }
    auth.users_.push_back({kDefaultTokenUser, hash});
  }
  if (auth.users_.empty()) {
    return absl::InvalidArgumentError(
        "no users: give --users FILE, --token TOKEN, --token-file FILE or set VPM_TOKEN "
        "(or --no-auth for local use)");
  }
  return auth;
}

Result<std::string> TokenAuth::Authenticate(const grpc::ServerContextBase& context) const {
  if (disabled_) return std::string(kNoAuthUser);
  const auto& metadata = context.client_metadata();
  auto it = metadata.find("authorization");
  if (it == metadata.end()) {
    return absl::UnauthenticatedError("missing 'authorization: Bearer TOKEN' metadata");
  }
  const std::string_view value(it->second.data(), it->second.size());
  constexpr std::string_view kPrefix = "Bearer ";
  if (!value.starts_with(kPrefix)) return absl::UnauthenticatedError("wrong bearer token");
  // Every user's hash is compared, so the time taken says nothing of which
  // (or whether one) matched.
  const std::string hash = HashToken(value.substr(kPrefix.size()));
  const UserCredential* match = nullptr;
  for (const UserCredential& user : users_) {
    if (ConstantTimeEquals(hash, user.token_sha256_hex)) match = &user;
  }
  if (match == nullptr) return absl::UnauthenticatedError("wrong bearer token");
  return match->name;
}

bool TokenAuth::HasUser(std::string_view name) const {
  for (const UserCredential& user : users_) {
    if (user.name == name) return true;
  }
  return false;
}

bool TokenAuth::MayBrowseDataRoot(std::string_view name) const {
  if (disabled_) return true;
  for (const UserCredential& user : users_) {
    if (user.name == name) return user.browse_data_root;
  }
  return false;
}

std::vector<std::string> TokenAuth::user_names() const {
  std::vector<std::string> names;
  for (const UserCredential& user : users_) names.push_back(user.name);
  return names;
}

}  // namespace vpm::service
