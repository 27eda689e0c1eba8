// A case as one portable message (vpm.v3.CaseArchive, docs/CASES.md): its
// source, mesh parameters, camera, title, notes and events in effect, the
// events' points and vectors in world LPS mm (the store keeps physical
// voxel space). The volume is referenced by its source, not embedded.
#pragma once

#include <vector>

#include "server/cases/case_record.h"
#include "server/volume/volume.h"
#include "vpm/v3/vpm.pb.h"

namespace vpm::service {

inline constexpr int kCaseArchiveVersion = 1;
inline constexpr int kMaxArchiveEvents = 100000;

v3::CaseArchive ToCaseArchive(const cases::CaseRecord& record,
                              const std::vector<cases::CaseEvent>& events,
                              const VolumeGeometry& geometry);

// The archive's events in physical voxel space. InvalidArgument naming the
// event and field for an unknown version or kind, a non-finite number, a
// point outside the volume, too many events.
Result<std::vector<cases::CaseEvent>> EventsFromArchive(const v3::CaseArchive& archive,
                                                        const VolumeGeometry& geometry);

}  // namespace vpm::service
