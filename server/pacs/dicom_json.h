// QIDO-RS answers (DICOM JSON, PS3.18 F.2) turned into the summaries a
// search and a series listing show.
#pragma once

#include <cstdint>
#include <string>
#include <string_view>
#include <vector>

#include "server/common/status.h"

namespace vpm::pacs {

struct StudySummary {
  std::string study_uid;     // StudyInstanceUID
  std::string patient_name;  // PN, Alphabetic group, "^" kept
  std::string patient_id;
  std::string patient_birth_date;  // YYYYMMDD as sent
  std::string study_date;
  std::string study_description;
  std::string accession_number;
  std::vector<std::string> modalities;  // ModalitiesInStudy
  int64_t series_count = -1;            // NumberOfStudyRelatedSeries; -1: not sent
  int64_t instance_count = -1;          // NumberOfStudyRelatedInstances
};

struct SeriesSummary {
  std::string series_uid;  // SeriesInstanceUID
  std::string modality;
  std::string description;  // SeriesDescription
  std::string body_part;    // BodyPartExamined
  int64_t series_number = 0;
  int64_t instance_count = -1;  // NumberOfSeriesRelatedInstances; -1: not sent
};

struct InstanceSummary {
  std::string sop_uid;              // SOPInstanceUID
  int64_t instance_number = 0;      // InstanceNumber; 0: not sent
};

// Parse a QIDO-RS answer body (a JSON list; an empty body is no match).
// Entries without a valid UID are skipped. InvalidArgument ("the PACS's
// answer: ...") for anything that is not a list of objects.
Result<std::vector<StudySummary>> ParseStudies(std::string_view body);
Result<std::vector<SeriesSummary>> ParseSeries(std::string_view body);
Result<std::vector<InstanceSummary>> ParseInstances(std::string_view body);

// The instance in the middle of `instances` by InstanceNumber (ties in the
// given order), the one a series' thumbnail shows; nullptr when empty.
const InstanceSummary* MiddleInstance(const std::vector<InstanceSummary>& instances);

}  // namespace vpm::pacs
