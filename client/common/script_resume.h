// Where a script goes on after its session was lost and its case reopened
// (`vpm play`): the script index after the last manipulation the case
// holds, so that none is sent twice and none is skipped.
//
// A stream's manipulations reach the case in order, but the server replaces
// a queued drag with the next one when they arrive faster than it applies
// them (FrameStream::EnqueueEvent), so a case holds the script's
// manipulations with some drags left out; a refinement on grab adds a
// REMESH of the server's own. Counting the case's events would then put the
// resume point before drags already applied, and send them again.
#pragma once

#include <cstdint>
#include <span>

#include "client/common/script_player.h"
#include "vpm/v3/vpm.pb.h"
#include "server/common/status.h"

namespace vpm::cli {

// The case's events (CaseArchive::events, in effect, in order) matched
// against the script's grabs, drags, pulls, releases, pins and resets in
// order: a drag by its offset (within 1e-4 mm), a pull by its force, a
// release by its keep, the others by kind; a script drag no event matches
// was replaced in the server's queue, which only a drag right after it
// does. Returns the index after the script event that the case's last
// manipulation matched (0 for none).
// NotFound when the events are not the script's in that sense (another
// client or an undo changed the case).
Result<int64_t> IndexAfterCaseEvents(const Script& script,
                                     std::span<const v3::CaseArchiveEvent> events);

// The script index after its first `manipulations` manipulations: the
// resume point when the case's events are not known.
int64_t IndexAfterManipulations(const Script& script, int64_t manipulations);

}  // namespace vpm::cli
