// Which client events are manipulations (grab, drag, pull, release, pin,
// reset): what a case stores and counts as its events, shared by the server
// (Session::StoreInCase) and the clients (where `vpm play` resumes a case).
#pragma once

#include "vpm/v3/vpm.pb.h"

namespace vpm {

inline bool IsManipulation(const v3::ClientEvent& event) {
  switch (event.event_case()) {
    case v3::ClientEvent::kGrab:
    case v3::ClientEvent::kDrag:
    case v3::ClientEvent::kPull:
    case v3::ClientEvent::kRelease:
    case v3::ClientEvent::kPin:
    case v3::ClientEvent::kReset:
      return true;
    default:
      return false;
  }
}

}  // namespace vpm
