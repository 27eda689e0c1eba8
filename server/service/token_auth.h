// Bearer-token check for every vpm.v2.Vpm call: `authorization: Bearer
// TOKEN` metadata. Health checking and reflection are other services and
// never reach it, so probes answer without a token.
#pragma once

#include <string>

#include <grpcpp/server_context.h>

#include "server/common/status.h"

namespace vpm::service {

class TokenAuth {
 public:
  struct Options {
    std::string token;     // required unless disabled
    bool disabled = false; // --no-auth
  };
  // InvalidArgument when there is neither a token nor an explicit opt-out.
  static Result<TokenAuth> Create(const Options& options);

  // Unauthenticated (without saying which part is wrong) unless the call
  // carries the token; compared in constant time.
  Status Check(const grpc::ServerContextBase& context) const;
  bool enabled() const { return !options_.disabled; }

 private:
  explicit TokenAuth(Options options) : options_(std::move(options)) {}
  Options options_;
};

}  // namespace vpm::service
