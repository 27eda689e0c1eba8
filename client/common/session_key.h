// The affinity key every call carries as `x-vpm-session` metadata. A
// balancer in front of several vpm-server replicas (docker/haproxy.cfg)
// hashes it to pick the replica, so all the calls made with one key
// (LoadVolume, BuildMesh, OpenSession, Interact, ...) meet the same volumes,
// meshes and sessions. The key is chosen by the client before its first call:
// the session id cannot be the key, since it is only known after
// OpenSession, which must itself reach the replica the later calls go to.
#pragma once

#include <string>

namespace vpm::cli {

inline constexpr char kSessionKeyHeader[] = "x-vpm-session";

// The key when none is given: env VPM_SESSION_KEY, else "user-" and 16 hex
// digits of SHA-256("USER@HOST"), the same for every vpm and vpm-view run of
// one user on one machine (so `vpm session open` and a later
// `vpm manipulate --session ID` meet the same replica) without sending
// the user or host name.
std::string DefaultSessionKey();

}  // namespace vpm::cli
