// A closed-loop drag on an Interact stream that is already grabbing: one
// drag event is sent per frame read, so the client never runs ahead of the
// server. The offset swings along x, 3 mm * sin(0.3 * sequence), so every
// event moves the grab. Used by the render storm's test and benchmark.
#pragma once

#include <cstdint>

#include <grpcpp/grpcpp.h>

#include "vpm/v3/vpm.grpc.pb.h"

namespace vpm::cli {

struct ClosedLoopDrag {
  int frames = 0;               // frames received
  double longest_wait_s = 0;    // longest wait from an event to its frame
};

// Drags for `seconds` (wall clock); `sequence` is the stream's event
// sequence number, advanced by one per event. Stops early when the stream
// breaks.
ClosedLoopDrag DragFor(grpc::ClientReaderWriter<v3::InteractRequest, v3::Frame>* stream,
                       double seconds, uint64_t* sequence);

}  // namespace vpm::cli
