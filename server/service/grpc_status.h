// The boundary between vpm's absl::Status values and gRPC: the codes are the
// same numbers (server/common/status.h), so the mapping is one to one.
#pragma once

#include <grpcpp/support/status.h>

#include "server/common/status.h"

namespace vpm::service {

// The longest status message a client receives, bytes. gRPC sends the
// message percent-encoded in the trailers (up to 3 bytes per byte); past about
// 64 KiB the trailers never go out and the call, and with it the client's
// whole HTTP/2 connection, stalls. Every message is cut here, whatever it
// quotes.
inline constexpr size_t kMaxStatusMessageBytes = 1024;

// `message` cut to at most kMaxStatusMessageBytes, at a UTF-8 character
// boundary, ending in "... (N bytes cut)" when cut.
std::string BoundedStatusMessage(absl::string_view message);

// The one conversion of a vpm Status to what gRPC sends: the same code, the
// message bounded.
grpc::Status ToGrpcStatus(const Status& status);

// gRPC's canonical name of a code ("OK", "NOT_FOUND"), for metrics labels.
const char* StatusCodeName(grpc::StatusCode code);

}  // namespace vpm::service
