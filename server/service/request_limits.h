// The length of every string a client sends, checked before any handler uses
// it: a request with a 70,000-byte session id is InvalidArgument at once,
// naming the field and its size, never quoting it.
#pragma once

#include <cstddef>

#include <google/protobuf/message.h>

#include "server/common/status.h"

namespace vpm::service {

// Bytes, per string field (bytes fields, such as an upload's chunks, are not
// strings and are not checked here).
inline constexpr size_t kMaxIdBytes = 128;            // fields named *_id
inline constexpr size_t kMaxTextBytes = size_t{1} << 20;  // `text`: a transfer-function file
inline constexpr size_t kMaxStringBytes = 8192;       // any other: sources, names, tags

// Walks `request` (nested messages and repeated fields included) and returns
// InvalidArgument for the first string over its limit: "session_id: 70000
// bytes; at most 128".
Status CheckRequestLimits(const google::protobuf::Message& request);

}  // namespace vpm::service
