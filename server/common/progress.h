// Progress of a long operation (a load, an export, a mesh build), for
// progress bars and the server's load status: `fraction` of the whole in
// [0, 1] and the stage it is in ("reading", "uploading", ...). Reporters may
// call it from any thread; an empty ProgressFn reports nowhere.
#pragma once

#include <algorithm>
#include <functional>
#include <memory>
#include <mutex>
#include <string_view>

namespace vpm {

using ProgressFn = std::function<void(double fraction, std::string_view stage)>;

// Reports into [begin, end] of `parent`: fraction f becomes begin + f * (end
// - begin). Empty when the parent is.
inline ProgressFn SubProgress(const ProgressFn& parent, double begin, double end) {
  if (!parent) return {};
  return [parent, begin, end](double f, std::string_view stage) {
    parent(begin + std::clamp(f, 0.0, 1.0) * (end - begin), stage);
  };
}

// Passes every report on with its fraction clamped to [0, 1] and raised to
// the largest passed so far, so that what a user sees never goes back, even
// when a reader reports two files in turn.
inline ProgressFn MonotoneProgress(ProgressFn sink) {
  if (!sink) return {};
  struct State {
    std::mutex mutex;
    double last = 0.0;
  };
  return [sink = std::move(sink), state = std::make_shared<State>()](double f,
                                                                      std::string_view stage) {
    std::lock_guard lock(state->mutex);
    f = std::clamp(f, 0.0, 1.0);
    if (f < state->last) f = state->last;
    state->last = f;
    sink(f, stage);
  };
}

}  // namespace vpm
