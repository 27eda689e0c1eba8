// The work of ExportDicom (docs/PACS.md, "Export"): the session's deformed
// volume as a derived series and its 3D frame as a secondary capture, in
// the source's study; sent to a PACS endpoint (STOW-RS) or handed back file
// by file. Runs on the request pool; the reactor (export_dicom_reactor.h)
// streams what it emits.
#pragma once

#include <functional>
#include <string>

#include "server/common/cancel_token.h"
#include "server/common/status.h"
#include "server/service/service_context.h"
#include "vpm/v3/vpm.pb.h"

namespace vpm::service {

// Receives each message to stream, in order (progress, files, the summary
// last); an error stops the export (the client went away).
using ExportEmit = std::function<Status(v3::ExportDicomPart part)>;

// Errors: InvalidArgument (no session id, a description over 64
// characters, a source modality other than CT or MR), NotFound /
// PermissionDenied for the session as Get gives them (its owner only),
// FailedPrecondition without --pacs when an endpoint is named, the PACS's
// errors (StoreExport), `cancel`'s.
Status RunDicomExport(ServiceContext* service, const std::string& user,
                      const v3::ExportDicomRequest& request, const ExportEmit& emit,
                      const CancelToken& cancel);

}  // namespace vpm::service
