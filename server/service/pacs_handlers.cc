// The PACS RPCs of VpmService (ListPacsEndpoints, SearchStudies,
// ListSeries, GetSeriesThumbnail, ExportDicom's reactor): translation
// between the API and server/pacs's PacsGateway, on the request pool (a
// PACS may take seconds to answer). LoadVolume of pacs: sources goes
// through the volume store (vpm_server.cc wires its read_pacs hook).
#include "server/pacs/pacs_source.h"
#include "server/service/export_dicom_reactor.h"
#include "server/service/vpm_service.h"

namespace vpm::service {
namespace {

Result<pacs::PacsGateway*> Gateway(ServiceContext* service) {
  if (service->pacs == nullptr) {
    return absl::FailedPreconditionError(
        "this server has no PACS endpoints (vpm-server --pacs FILE)");
  }
  return service->pacs;
}

void FillStudy(const pacs::StudySummary& s, v3::StudyInfo* out) {
  out->set_study_uid(s.study_uid);
  out->set_patient_name(s.patient_name);
  out->set_patient_id(s.patient_id);
  out->set_patient_birth_date(s.patient_birth_date);
  out->set_study_date(s.study_date);
  out->set_study_description(s.study_description);
  out->set_accession_number(s.accession_number);
  for (const std::string& m : s.modalities) out->add_modalities(m);
  out->set_series_count(s.series_count);
  out->set_instance_count(s.instance_count);
}

}  // namespace

grpc::ServerUnaryReactor* VpmService::ListPacsEndpoints(grpc::CallbackServerContext* context,
                                                        const v3::ListPacsEndpointsRequest*,
                                                        v3::ListPacsEndpointsResponse* response) {
  return Unary(context, "ListPacsEndpoints", service_->request_pool,
               [=, this](const std::string& user) -> Status {
                 if (service_->pacs == nullptr) return absl::OkStatus();
                 for (const std::string& name : service_->pacs->EndpointsFor(user))
                   response->add_endpoints(name);
                 return absl::OkStatus();
               });
}

grpc::ServerWriteReactor<v3::ExportDicomPart>* VpmService::ExportDicom(
    grpc::CallbackServerContext* context, const v3::ExportDicomRequest* request) {
  return ExportDicomReactor::Make(service_, context, *request);
}

grpc::ServerUnaryReactor* VpmService::SearchStudies(grpc::CallbackServerContext* context,
                                                    const v3::SearchStudiesRequest* request,
                                                    v3::SearchStudiesResponse* response) {
  return Unary(context, *request, "SearchStudies", service_->request_pool,
               [=, this](const std::string& user, const CancelToken& cancel) -> Status {
                 ASSIGN_OR_RETURN(pacs::PacsGateway * gateway, Gateway(service_));
                 if (request->endpoint().empty())
                   return absl::InvalidArgumentError("endpoint: required");
                 pacs::StudyQuery query{.patient_name = request->patient_name(),
                                        .patient_id = request->patient_id(),
                                        .patient_birth_date = request->patient_birth_date(),
                                        .study_date = request->study_date(),
                                        .modality = request->modality(),
                                        .accession_number = request->accession_number(),
                                        .limit = request->limit() == 0 ? 100 : request->limit()};
                 ASSIGN_OR_RETURN(const pacs::StudySearch found,
                                  gateway->SearchStudies(user, request->endpoint(), query, cancel));
                 for (const pacs::StudySummary& s : found.studies)
                   FillStudy(s, response->add_studies());
                 response->set_truncated(found.truncated);
                 return absl::OkStatus();
               });
}

grpc::ServerUnaryReactor* VpmService::ListSeries(grpc::CallbackServerContext* context,
                                                 const v3::ListSeriesRequest* request,
                                                 v3::ListSeriesResponse* response) {
  return Unary(context, *request, "ListSeries", service_->request_pool,
               [=, this](const std::string& user, const CancelToken& cancel) -> Status {
                 ASSIGN_OR_RETURN(pacs::PacsGateway * gateway, Gateway(service_));
                 if (request->endpoint().empty())
                   return absl::InvalidArgumentError("endpoint: required");
                 ASSIGN_OR_RETURN(
                     const std::vector<pacs::SeriesSummary> series,
                     gateway->ListSeries(user, request->endpoint(), request->study_uid(), cancel));
                 for (const pacs::SeriesSummary& s : series) {
                   v3::SeriesInfo* out = response->add_series();
                   out->set_series_uid(s.series_uid);
                   out->set_modality(s.modality);
                   out->set_description(s.description);
                   out->set_body_part(s.body_part);
                   out->set_series_number(s.series_number);
                   out->set_instance_count(s.instance_count);
                   out->set_source(StrCat(pacs::kPacsPrefix, request->endpoint(), "/",
                                          request->study_uid(), "/", s.series_uid));
                 }
                 return absl::OkStatus();
               });
}

grpc::ServerUnaryReactor* VpmService::GetSeriesThumbnail(
    grpc::CallbackServerContext* context, const v3::GetSeriesThumbnailRequest* request,
    v3::SeriesThumbnail* response) {
  return Unary(context, *request, "GetSeriesThumbnail", service_->request_pool,
               [=, this](const std::string& user, const CancelToken& cancel) -> Status {
                 ASSIGN_OR_RETURN(pacs::PacsGateway * gateway, Gateway(service_));
                 if (request->endpoint().empty())
                   return absl::InvalidArgumentError("endpoint: required");
                 ASSIGN_OR_RETURN(pacs::SeriesThumbnail thumbnail,
                                  gateway->GetSeriesThumbnail(
                                      user, request->endpoint(), request->study_uid(),
                                      request->series_uid(), request->size_px(), cancel));
                 response->set_png(thumbnail.png.data(), thumbnail.png.size());
                 response->set_width(thumbnail.width);
                 response->set_height(thumbnail.height);
                 return absl::OkStatus();
               });
}

}  // namespace vpm::service
