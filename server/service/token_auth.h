// Who is calling: every vpm.v3.Vpm call carries `authorization: Bearer
// TOKEN` metadata, and the token names a user. Users come from --users (a
// file of names and token hashes, users_file.h) and from the single
// --token (or --token-file, or VPM_TOKEN), which is the user `default`.
// Only SHA-256 hashes of tokens are held; a presented token is hashed and
// compared with every user's hash in constant time. Health checking and
// reflection are other services and never reach this, so probes answer
// without a token. With --no-auth every caller is the user `local`.
#pragma once

#include <string>
#include <vector>

#include <grpcpp/server_context.h>

#include "server/common/status.h"
#include "server/service/users_file.h"

namespace vpm::service {

inline constexpr char kDefaultTokenUser[] = "default";  // the --token user
inline constexpr char kNoAuthUser[] = "local";          // every caller under --no-auth

class TokenAuth {
 public:
  struct Options {
    std::string token;                  // the user `default`; empty: none
    std::vector<UserCredential> users;  // from --users
    bool disabled = false;              // --no-auth
  };
  // InvalidArgument when there is no user and no explicit opt-out, when
  // --no-auth comes with a users file, or when the --token user clashes
  // with one of the file (same name or same token).
  static Result<TokenAuth> Create(const Options& options);

  // The caller's user name; Unauthenticated (without saying which part is
  // wrong) unless the call carries a known token.
  Result<std::string> Authenticate(const grpc::ServerContextBase& context) const;
  // Authenticate without the name.
  Status Check(const grpc::ServerContextBase& context) const {
    return Authenticate(context).status();
  }
  bool enabled() const { return !disabled_; }
  // Whether `name` is a user of this server (session sharing names one).
  bool HasUser(std::string_view name) const;
  std::vector<std::string> user_names() const;
  // Whether `name` may list the data root (ListDataRoot): a user of the
  // users file given `browse-data-root`, or everyone under --no-auth (a
  // loopback-only server of one person). The --token user `default` may
  // not: it is often a shared viewer token (docs/SERVICE.md).
  bool MayBrowseDataRoot(std::string_view name) const;

 private:
  TokenAuth() = default;
  bool disabled_ = false;
  std::vector<UserCredential> users_;
};

}  // namespace vpm::service
