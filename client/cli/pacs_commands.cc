#include "client/cli/pacs_commands.h"

#include <cstdio>
#include <memory>
#include <string>

#include "client/common/proto_json.h"
#include "client/cli/server_flags.h"
#include "server/common/write_file.h"

namespace vpm::cli {
namespace {

using nlohmann::json;

std::string Count(int64_t n) { return n < 0 ? "?" : std::to_string(n); }

std::string Joined(const google::protobuf::RepeatedPtrField<std::string>& values) {
  std::string out;
  for (const std::string& v : values) out += (out.empty() ? "" : ",") + v;
  return out;
}

json StudyJson(const v3::StudyInfo& s) {
  return {
      {"study_uid", s.study_uid()},
      {"patient_name", s.patient_name()},
      {"patient_id", s.patient_id()},
      {"patient_birth_date", s.patient_birth_date()},
      {"study_date", s.study_date()},
      {"study_description", s.study_description()},
      {"accession_number", s.accession_number()},
      {"modalities", json(std::vector<std::string>(s.modalities().begin(), s.modalities().end()))},
      {"series_count", s.series_count()},
      {"instance_count", s.instance_count()}};
}

json SeriesJson(const v3::SeriesInfo& s) {
  return {{"series_uid", s.series_uid()},
          {"modality", s.modality()},
          {"description", s.description()},
          {"body_part", s.body_part()},
          {"series_number", s.series_number()},
          {"instance_count", s.instance_count()},
          {"source", s.source()}};
}

struct SearchArgs {
  v3::SearchStudiesRequest request;
  std::string endpoint, patient_name, patient_id, birth_date, study_date, modality, accession;
  int limit = 0;
  bool json = false;
};

Status Search(const ServerConnection& s, const SearchArgs& a) {
  v3::SearchStudiesRequest request;
  request.set_endpoint(a.endpoint);
  request.set_patient_name(a.patient_name);
  request.set_patient_id(a.patient_id);
  request.set_patient_birth_date(a.birth_date);
  request.set_study_date(a.study_date);
  request.set_modality(a.modality);
  request.set_accession_number(a.accession);
  request.set_limit(a.limit);
  v3::SearchStudiesResponse response;
  RETURN_IF_ERROR(FromGrpc(s.stub().SearchStudies(s.Context().get(), request, &response)));
  if (a.json) {
    json studies = json::array();
    for (const auto& study : response.studies()) studies.push_back(StudyJson(study));
    PrintJson({{"studies", studies}, {"truncated", response.truncated()}});
    return absl::OkStatus();
  }
  std::printf("%-10s %-24s %-14s %-10s %-10s %-6s %s\n", "DATE", "PATIENT", "ID", "BIRTH",
              "MODALITY", "SERIES", "STUDY UID / DESCRIPTION");
  for (const auto& st : response.studies()) {
    std::printf("%-10s %-24s %-14s %-10s %-10s %-6s %s  %s\n", st.study_date().c_str(),
                st.patient_name().c_str(), st.patient_id().c_str(), st.patient_birth_date().c_str(),
                Joined(st.modalities()).c_str(), Count(st.series_count()).c_str(),
                st.study_uid().c_str(), st.study_description().c_str());
  }
  std::printf(
      "%d studies%s\n", response.studies_size(),
      response.truncated() ? " (the limit was reached: narrow the search or raise --limit)" : "");
  return absl::OkStatus();
}

struct SeriesArgs {
  std::string endpoint, study;
  bool json = false;
};

Status Series(const ServerConnection& s, const SeriesArgs& a) {
  v3::ListSeriesRequest request;
  request.set_endpoint(a.endpoint);
  request.set_study_uid(a.study);
  v3::ListSeriesResponse response;
  RETURN_IF_ERROR(FromGrpc(s.stub().ListSeries(s.Context().get(), request, &response)));
  if (a.json) {
    json series = json::array();
    for (const auto& one : response.series()) series.push_back(SeriesJson(one));
    PrintJson({{"series", series}});
    return absl::OkStatus();
  }
  std::printf("%-4s %-8s %-7s %-12s %-32s %s\n", "NO", "MODALITY", "IMAGES", "BODY PART",
              "DESCRIPTION", "SOURCE (vpm volume load ...)");
  for (const auto& one : response.series()) {
    std::printf("%-4lld %-8s %-7s %-12s %-32s %s\n", static_cast<long long>(one.series_number()),
                one.modality().c_str(), Count(one.instance_count()).c_str(),
                one.body_part().c_str(), one.description().c_str(), one.source().c_str());
  }
  return absl::OkStatus();
}

struct ThumbnailArgs {
  std::string endpoint, study, series, out;
  int size_px = 0;
};

Status Thumbnail(const ServerConnection& s, const ThumbnailArgs& a) {
  v3::GetSeriesThumbnailRequest request;
  request.set_endpoint(a.endpoint);
  request.set_study_uid(a.study);
  request.set_series_uid(a.series);
  request.set_size_px(a.size_px);
  v3::SeriesThumbnail response;
  RETURN_IF_ERROR(
      FromGrpc(s.stub().GetSeriesThumbnail(s.Context().get(), request, &response)));
  RETURN_IF_ERROR(WriteFile(a.out, response.png()));
  std::printf("%s: %d x %d PNG, %zu bytes\n", a.out.c_str(), response.width(), response.height(),
              response.png().size());
  return absl::OkStatus();
}

Status Endpoints(const ServerConnection& s, bool as_json) {
  v3::ListPacsEndpointsResponse response;
  RETURN_IF_ERROR(FromGrpc(
      s.stub().ListPacsEndpoints(s.Context().get(), v3::ListPacsEndpointsRequest(), &response)));
  const std::vector<std::string> names(response.endpoints().begin(), response.endpoints().end());
  if (as_json) {
    PrintJson({{"endpoints", names}});
  } else if (names.empty()) {
    std::printf("no PACS endpoint that you may use on this server\n");
  } else {
    for (const std::string& name : names) std::printf("%s\n", name.c_str());
  }
  return absl::OkStatus();
}

}  // namespace

void AddPacsCommands(CLI::App& app, const ServerFlags* flags, int* exit_code) {
  CLI::App* pacs =
      app.add_subcommand("pacs", "server: search a PACS and list series (--pacs on the server)");
  pacs->require_subcommand(1);

  auto endpoints_json = std::make_shared<bool>(false);
  CLI::App* e = pacs->add_subcommand("endpoints", "server: the PACS endpoints you may use");
  e->add_flag("--json", *endpoints_json, "print JSON");
  e->callback(WithServer(flags, exit_code, [endpoints_json](const ServerConnection& c) {
    return Endpoints(c, *endpoints_json);
  }));

  auto search = std::make_shared<SearchArgs>();
  CLI::App* s = pacs->add_subcommand("search", "server: SearchStudies (QIDO-RS) on an endpoint");
  s->add_option("--endpoint", search->endpoint, "endpoint name in the server's --pacs file")
      ->required();
  s->add_option("--patient-name", search->patient_name, "DICOM name, wildcards * and ?: 'DOE^J*'");
  s->add_option("--patient-id", search->patient_id, "patient ID");
  s->add_option("--birth-date", search->birth_date, "YYYYMMDD or FROM-TO");
  s->add_option("--study-date", search->study_date, "YYYYMMDD or FROM-TO (either end open)");
  s->add_option("--modality", search->modality, "a modality in the study: CT, MR, ...");
  s->add_option("--accession", search->accession, "accession number");
  s->add_option("--limit", search->limit, "most studies (1..1000; default 100)");
  s->add_flag("--json", search->json, "print JSON");
  s->callback(WithServer(flags, exit_code,
                         [search](const ServerConnection& c) { return Search(c, *search); }));

  auto series = std::make_shared<SeriesArgs>();
  CLI::App* l = pacs->add_subcommand("series", "server: ListSeries (QIDO-RS) of a study");
  l->add_option("--endpoint", series->endpoint, "endpoint name in the server's --pacs file")
      ->required();
  l->add_option("--study", series->study, "Study Instance UID")->required();
  l->add_flag("--json", series->json, "print JSON");
  l->callback(WithServer(flags, exit_code,
                         [series](const ServerConnection& c) { return Series(c, *series); }));

  auto thumbnail = std::make_shared<ThumbnailArgs>();
  CLI::App* t = pacs->add_subcommand(
      "thumbnail", "server: GetSeriesThumbnail, a grey PNG of one instance of a series");
  t->add_option("--endpoint", thumbnail->endpoint, "endpoint name in the server's --pacs file")
      ->required();
  t->add_option("--study", thumbnail->study, "Study Instance UID")->required();
  t->add_option("--series", thumbnail->series, "Series Instance UID")->required();
  t->add_option("--size", thumbnail->size_px, "the longer side, pixels (16..256; default 128)");
  t->add_option("--out", thumbnail->out, "the PNG file to write")->required();
  t->callback(WithServer(flags, exit_code, [thumbnail](const ServerConnection& c) {
    return Thumbnail(c, *thumbnail);
  }));
}

}  // namespace vpm::cli
