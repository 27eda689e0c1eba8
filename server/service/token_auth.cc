#include "server/service/token_auth.h"

#include <string_view>

namespace vpm::service {
namespace {

bool ConstantTimeEquals(std::string_view a, std::string_view b) {
  unsigned char diff = a.size() == b.size() ? 0 : 1;
  for (size_t i = 0; i < a.size(); ++i) {
    diff |= static_cast<unsigned char>(a[i] ^ (i < b.size() ? b[i] : 0));
  }
  return diff == 0;
}

}  // namespace

Result<TokenAuth> TokenAuth::Create(const Options& options) {
  if (!options.disabled && options.token.empty()) {
    return absl::InvalidArgumentError(
        "no token: give --token TOKEN or set VPM_TOKEN (or --no-auth for local use)");
  }
  return TokenAuth(options);
}

Status TokenAuth::Check(const grpc::ServerContextBase& context) const {
  if (options_.disabled) return absl::OkStatus();
  const auto& metadata = context.client_metadata();
  auto it = metadata.find("authorization");
  if (it == metadata.end()) {
    return absl::UnauthenticatedError("missing 'authorization: Bearer TOKEN' metadata");
  }
  const std::string_view value(it->second.data(), it->second.size());
  constexpr std::string_view kPrefix = "Bearer ";
  if (!value.starts_with(kPrefix) ||
      !ConstantTimeEquals(value.substr(kPrefix.size()), options_.token)) {
    return absl::UnauthenticatedError("wrong bearer token");
  }
  return absl::OkStatus();
}

}  // namespace vpm::service
