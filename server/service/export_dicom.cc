#include "server/service/export_dicom.h"

#include <cstdio>

#include "server/io/write_derived_series.h"
#include "server/io/write_secondary_capture.h"

namespace vpm::service {
namespace {

std::string Mm(double v) {
  char text[32];
  std::snprintf(text, sizeof text, "%.1f", v);
  return text;
}

DerivedSeriesText DescribeExport(const Session::Exported& state, const std::string& source,
                                 const std::string& asked) {
  DerivedSeriesText text;
  text.series_description =
      asked.empty() ? StrCat("vpm deformed, max ", Mm(state.max_displacement_mm), " mm") : asked;
  text.derivation_description =
      StrCat("Deformed by vpm (volume proxy mesh, corotational FEM): ", state.manipulations,
             " manipulation(s) since the last reset; largest tissue displacement ",
             Mm(state.max_displacement_mm), " mm");
  if (state.grab_world_mm) {
    const glm::dvec3& g = *state.grab_world_mm;
    text.derivation_description +=
        StrCat("; grab at LPS (", Mm(g.x), ", ", Mm(g.y), ", ", Mm(g.z), ") mm");
  }
  // The source's own path stays out: it may name a patient folder.
  text.derivation_description += source.starts_with("pacs:") ? "; source: the referenced series"
                                                             : "; source: a vpm volume";
  if (text.derivation_description.size() > 1024) text.derivation_description.resize(1024);
  return text;
}

v3::ExportDicomPart Progress(const char* stage, double fraction) {
  v3::ExportDicomPart part;
  part.set_stage(stage);
  part.set_fraction(fraction);
  return part;
}

// The files sent to `endpoint` (STOW-RS or C-STORE), progress emitted.
Status SendExport(ServiceContext* service, const std::string& user, const std::string& endpoint,
                  const std::vector<DicomFileBytes>& files, const DicomExportIds& ids,
                  const ExportEmit& emit, const CancelToken& cancel) {
  std::vector<const std::string*> parts;
  for (const DicomFileBytes& f : files) parts.push_back(&f.bytes);
  return service->pacs->StoreExport(
      user, endpoint, parts, ids.study_uid, ids.derived_series_uid,
      [&](double f, std::string_view) { (void)emit(Progress("sending", f)); }, cancel);
}

// The files back to the client, one message each (the capture last).
Status StreamExport(ServiceContext* service, const std::string& user,
                    std::vector<DicomFileBytes> files, const DicomExportIds& ids,
                    const ExportEmit& emit) {
  const size_t count = files.size();
  for (size_t n = 0; n < count; ++n) {
    v3::ExportDicomPart part;
    part.set_file_name(n + 1 < count ? "derived/" + files[n].name : "capture/000001.dcm");
    part.set_data(std::move(files[n].bytes));
    RETURN_IF_ERROR(emit(std::move(part)));
  }
  if (service->pacs != nullptr) {
    service->pacs->RecordExport(user, ids.study_uid, ids.derived_series_uid, absl::OkStatus(),
                                static_cast<int64_t>(count));
  }
  return absl::OkStatus();
}

}  // namespace

Status RunDicomExport(ServiceContext* service, const std::string& user,
                      const v3::ExportDicomRequest& request, const ExportEmit& emit,
                      const CancelToken& cancel) {
  if (request.session_id().empty()) return absl::InvalidArgumentError("session_id: required");
  if (request.series_description().size() > 64) {
    return absl::InvalidArgumentError("series_description: at most 64 characters");
  }
  if (!request.endpoint().empty() && service->pacs == nullptr) {
    return absl::FailedPreconditionError(
        "this server has no PACS endpoints (vpm-server --pacs FILE)");
  }
  ASSIGN_OR_RETURN(std::shared_ptr<Session> session,
                   service->sessions->Get(request.session_id(), user, SessionRole::kOwner));
  RETURN_IF_ERROR(emit(Progress("warping", 0.0)));
  ASSIGN_OR_RETURN(const Session::Exported state, session->Export(cancel));
  const Volume& source = session->volume().volume;
  const DicomOrigin* origin = source.dicom_origin().get();
  const DicomExportIds ids = MakeDicomExportIds(origin);
  const DerivedSeriesText text = DescribeExport(state, source.source(), request.series_description());
  ASSIGN_OR_RETURN(std::vector<DicomFileBytes> files,
                   WriteDerivedSeries(state.deformed, origin, ids, text,
                                      [&](double f, std::string_view) {
                                        if (f == 1.0 || int(f * 100) % 10 == 0) (void)emit(Progress("writing", f));
                                      }));
  ASSIGN_OR_RETURN(std::string capture,
                   WriteSecondaryCapture(state.frame.rgba, state.frame.width, state.frame.height,
                                         origin, ids, "vpm 3D view"));
  files.push_back({"capture.dcm", std::move(capture)});
  RETURN_IF_ERROR(cancel.Check());
  v3::ExportDicomSummary summary;
  summary.set_study_uid(ids.study_uid);
  summary.set_derived_series_uid(ids.derived_series_uid);
  summary.set_capture_series_uid(ids.capture_series_uid);
  summary.set_instances(static_cast<int32_t>(files.size()));
  summary.set_series_description(text.series_description);
  summary.set_max_displacement_mm(state.max_displacement_mm);
  int64_t bytes = 0;
  for (const DicomFileBytes& f : files) bytes += int64_t(f.bytes.size());
  summary.set_bytes(bytes);
  if (!request.endpoint().empty()) {
    RETURN_IF_ERROR(SendExport(service, user, request.endpoint(), files, ids, emit, cancel));
    summary.set_endpoint(request.endpoint());
  } else {
    RETURN_IF_ERROR(StreamExport(service, user, std::move(files), ids, emit));
  }
  v3::ExportDicomPart last;
  *last.mutable_summary() = summary;
  return emit(std::move(last));
}

}  // namespace vpm::service
