// What a QIDO-RS study search asks for, checked, and its query string.
#pragma once

#include <cstdint>
#include <string>

#include "server/common/status.h"

namespace vpm::pacs {

// Empty fields are not sent. Matching is the PACS's (DICOM PS3.18 QIDO-RS):
// `patient_name` may hold the wildcards '*' and '?', and fuzzy matching is
// off; dates are YYYYMMDD, a range FROM-TO (either end may be left open).
struct StudyQuery {
  std::string patient_name;  // e.g. "DOE^J*"
  std::string patient_id;
  std::string patient_birth_date;  // YYYYMMDD or a range
  std::string study_date;          // YYYYMMDD or a range, e.g. 20240101-20241231
  std::string modality;            // ModalitiesInStudy, e.g. CT
  std::string accession_number;
  int64_t limit = 100;  // most studies returned, 1..1000
};

// InvalidArgument naming the field (never quoting a patient identifier):
// control characters, a field over 64 bytes, a malformed date or range, a
// modality that is not 1-16 of [A-Z0-9], a limit outside 1..1000.
Status CheckStudyQuery(const StudyQuery& query);

// "PatientName=DOE^J*&...&includefield=...&limit=L&offset=O" (no '?'):
// wildcards and '^' as they are, '&', '=', '#', '+', '%', spaces and
// non-ASCII percent-encoded.
std::string StudyQueryString(const StudyQuery& query, int64_t limit, int64_t offset);

// The names of the filters set, for the audit log: "PatientName,StudyDate".
std::string StudyQueryFilters(const StudyQuery& query);

// OK for a DICOM UID (1-64 of digits and dots, not starting or ending with
// a dot); InvalidArgument naming `field` otherwise.
Status CheckUid(std::string_view uid, std::string_view field);

}  // namespace vpm::pacs
