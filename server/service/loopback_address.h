// Whether a gRPC listen address reaches only this machine: a loopback IP
// (127.0.0.0/8, ::1, ::ffff:127.x.y.z), "localhost", or a unix socket.
// `--no-auth` serves without a token, so it may listen only there.
#pragma once

#include <string_view>

namespace vpm::service {

// listen: "HOST:PORT", "[V6]:PORT" or "unix:PATH".
bool IsLoopbackAddress(std::string_view listen);

}  // namespace vpm::service
