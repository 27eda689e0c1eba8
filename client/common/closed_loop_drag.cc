#include "client/common/closed_loop_drag.h"

#include <algorithm>
#include <chrono>
#include <cmath>

namespace vpm::cli {

ClosedLoopDrag DragFor(grpc::ClientReaderWriter<v3::InteractRequest, v3::Frame>* stream,
                       double seconds, uint64_t* sequence) {
  using Clock = std::chrono::steady_clock;
  ClosedLoopDrag result;
  const auto end = Clock::now() + std::chrono::duration<double>(seconds);
  v3::Frame frame;
  while (Clock::now() < end) {
    v3::InteractRequest drag;
    drag.mutable_event()->set_sequence(++*sequence);
    drag.mutable_event()->mutable_drag()->mutable_offset_mm()->set_x(
        3.0 * std::sin(0.3 * double(*sequence)));
    const auto sent = Clock::now();
    if (!stream->Write(drag) || !stream->Read(&frame)) break;
    result.longest_wait_s = std::max(result.longest_wait_s,
                                     std::chrono::duration<double>(Clock::now() - sent).count());
    ++result.frames;
  }
  return result;
}

}  // namespace vpm::cli
