#include "server/pacs/study_query.h"

#include <algorithm>
#include <cctype>
#include <vector>


namespace vpm::pacs {
namespace {

bool IsDate(std::string_view d) {
  return d.size() == 8 &&
         std::all_of(d.begin(), d.end(), [](unsigned char c) { return std::isdigit(c); });
}

Status CheckDateRange(std::string_view value, const char* field) {
  if (value.empty()) return absl::OkStatus();
  const size_t dash = value.find('-');
  const bool ok = dash == std::string_view::npos
                      ? IsDate(value)
                      : (value.size() > 1 && value.find('-', dash + 1) == std::string_view::npos &&
                         (dash == 0 || IsDate(value.substr(0, dash))) &&
                         (dash + 1 == value.size() || IsDate(value.substr(dash + 1))));
  if (ok) return absl::OkStatus();
  return absl::InvalidArgumentError(
      StrCat(field, ": a date YYYYMMDD or a range FROM-TO (YYYYMMDD-YYYYMMDD, either end open)"));
}

Status CheckText(std::string_view value, const char* field) {
  if (value.size() > 64) {
    return absl::InvalidArgumentError(StrCat(field, ": ", value.size(), " bytes; at most 64"));
  }
  if (std::any_of(value.begin(), value.end(),
                  [](unsigned char c) { return c < 0x20 || c == 0x7f || c == '\\'; })) {
    return absl::InvalidArgumentError(
        StrCat(field, ": control characters and '\\' are not allowed"));
  }
  return absl::OkStatus();
}

// A query value as DICOMweb servers read it: the wildcards '*' and '?' and
// the PN separator '^' go as they are, because some servers (Orthanc 1.10)
// do not percent-decode query values; what would break the query's syntax
// ('&', '=', '#', '+', '%', spaces, non-ASCII) is percent-encoded.
std::string QueryValue(std::string_view value) {
  static const char* kHex = "0123456789ABCDEF";
  std::string out;
  for (unsigned char c : value) {
    if (std::isalnum(c) || std::string_view("-_.~*?^,:/!$'()@").find(static_cast<char>(c)) !=
                               std::string_view::npos) {
      out += static_cast<char>(c);
    } else {
      out += '%';
      out += kHex[c >> 4];
      out += kHex[c & 15];
    }
  }
  return out;
}

}  // namespace

Status CheckUid(std::string_view uid, std::string_view field) {
  const bool ok = !uid.empty() && uid.size() <= 64 && uid.front() != '.' && uid.back() != '.' &&
                  std::all_of(uid.begin(), uid.end(),
                              [](unsigned char c) { return std::isdigit(c) || c == '.'; });
  if (ok) return absl::OkStatus();
  return absl::InvalidArgumentError(
      StrCat(field, ": not a DICOM UID (1 to 64 digits and dots, e.g. 1.2.840.113619.2.55)"));
}

Status CheckStudyQuery(const StudyQuery& q) {
  RETURN_IF_ERROR(CheckText(q.patient_name, "patient_name"));
  RETURN_IF_ERROR(CheckText(q.patient_id, "patient_id"));
  RETURN_IF_ERROR(CheckText(q.accession_number, "accession_number"));
  RETURN_IF_ERROR(CheckDateRange(q.patient_birth_date, "patient_birth_date"));
  RETURN_IF_ERROR(CheckDateRange(q.study_date, "study_date"));
  if (!q.modality.empty() &&
      (q.modality.size() > 16 ||
       !std::all_of(q.modality.begin(), q.modality.end(),
                    [](unsigned char c) { return std::isupper(c) || std::isdigit(c); }))) {
    return absl::InvalidArgumentError("modality: 1 to 16 of A-Z and 0-9, e.g. CT or MR");
  }
  if (q.limit < 1 || q.limit > 1000) {
    return absl::InvalidArgumentError(StrCat("limit: ", q.limit, "; 1 to 1000"));
  }
  return absl::OkStatus();
}

std::string StudyQueryString(const StudyQuery& q, int64_t limit, int64_t offset) {
  std::vector<std::pair<const char*, const std::string*>> filters = {
      {"PatientName", &q.patient_name},
      {"PatientID", &q.patient_id},
      {"PatientBirthDate", &q.patient_birth_date},
      {"StudyDate", &q.study_date},
      {"ModalitiesInStudy", &q.modality},
      {"AccessionNumber", &q.accession_number}};
  std::string out;
  for (const auto& [key, value] : filters) {
    if (!value->empty()) StrAppend(&out, key, "=", QueryValue(*value), "&");
  }
  // Attributes QIDO-RS does not return by default.
  StrAppend(&out,
            "includefield=00081030&includefield=00080061&includefield=00201206"
            "&includefield=00201208&fuzzymatching=false&limit=",
            limit, "&offset=", offset);
  return out;
}

std::string StudyQueryFilters(const StudyQuery& q) {
  std::string out;
  auto add = [&](const std::string& value, const char* name) {
    if (!value.empty()) StrAppend(&out, out.empty() ? "" : ",", name);
  };
  add(q.patient_name, "PatientName");
  add(q.patient_id, "PatientID");
  add(q.patient_birth_date, "PatientBirthDate");
  add(q.study_date, "StudyDate");
  add(q.modality, "ModalitiesInStudy");
  add(q.accession_number, "AccessionNumber");
  return out;
}

}  // namespace vpm::pacs
