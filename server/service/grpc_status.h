// The boundary between vpm's absl::Status values and gRPC: the codes are the
// same numbers (server/common/status.h), so the mapping is one to one.
#pragma once

#include <grpcpp/support/status.h>

#include "server/common/status.h"

namespace vpm::service {

inline grpc::Status ToGrpcStatus(const Status& status) {
  if (status.ok()) return grpc::Status::OK;
  return grpc::Status(static_cast<grpc::StatusCode>(status.code()),
                      std::string(status.message()));
}

// gRPC's canonical name of a code ("OK", "NOT_FOUND"), for metrics labels.
const char* StatusCodeName(grpc::StatusCode code);

}  // namespace vpm::service
