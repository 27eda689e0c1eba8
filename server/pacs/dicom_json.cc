#include "server/pacs/dicom_json.h"

#include <algorithm>

#include <nlohmann/json.hpp>

#include "server/pacs/study_query.h"

namespace vpm::pacs {
namespace {

using nlohmann::json;

const json* FirstValue(const json& item, const char* tag) {
  auto it = item.find(tag);
  if (it == item.end() || !it->is_object()) return nullptr;
  auto value = it->find("Value");
  if (value == it->end() || !value->is_array() || value->empty()) return nullptr;
  return &(*value)[0];
}

std::string Text(const json& item, const char* tag) {
  const json* v = FirstValue(item, tag);
  if (v == nullptr) return "";
  if (v->is_string()) return v->get<std::string>();
  if (v->is_number_integer()) return std::to_string(v->get<int64_t>());
  if (v->is_object()) {  // PN
    auto alphabetic = v->find("Alphabetic");
    if (alphabetic != v->end() && alphabetic->is_string()) return alphabetic->get<std::string>();
  }
  return "";
}

int64_t Number(const json& item, const char* tag, int64_t absent) {
  const json* v = FirstValue(item, tag);
  if (v == nullptr) return absent;
  if (v->is_number_integer()) return v->get<int64_t>();
  if (v->is_number()) return static_cast<int64_t>(v->get<double>());
  if (v->is_string()) {
    try {
      return std::stoll(v->get<std::string>());
    } catch (...) {
      return absent;
    }
  }
  return absent;
}

std::vector<std::string> Texts(const json& item, const char* tag) {
  std::vector<std::string> out;
  auto it = item.find(tag);
  if (it == item.end() || !it->is_object()) return out;
  auto value = it->find("Value");
  if (value == it->end() || !value->is_array()) return out;
  for (const json& v : *value) {
    if (v.is_string()) out.push_back(v.get<std::string>());
  }
  return out;
}

Result<json> ParseList(std::string_view body) {
  if (body.find_first_not_of(" \t\r\n") == std::string_view::npos) return json::array();
  json parsed = json::parse(body, nullptr, /*allow_exceptions=*/false);
  if (parsed.is_discarded()) return absl::InvalidArgumentError("the PACS's answer is not JSON");
  if (!parsed.is_array()) return absl::InvalidArgumentError("the PACS's answer is not a JSON list");
  for (const json& item : parsed) {
    if (!item.is_object()) {
      return absl::InvalidArgumentError("the PACS's answer holds an entry that is not an object");
    }
  }
  return parsed;
}

}  // namespace

Result<std::vector<StudySummary>> ParseStudies(std::string_view body) {
  ASSIGN_OR_RETURN(const json list, ParseList(body));
  std::vector<StudySummary> out;
  for (const json& item : list) {
    StudySummary s;
    s.study_uid = Text(item, "0020000D");
    if (!CheckUid(s.study_uid, "").ok()) continue;
    s.patient_name = Text(item, "00100010");
    s.patient_id = Text(item, "00100020");
    s.patient_birth_date = Text(item, "00100030");
    s.study_date = Text(item, "00080020");
    s.study_description = Text(item, "00081030");
    s.accession_number = Text(item, "00080050");
    s.modalities = Texts(item, "00080061");
    s.series_count = Number(item, "00201206", -1);
    s.instance_count = Number(item, "00201208", -1);
    out.push_back(std::move(s));
  }
  return out;
}

Result<std::vector<SeriesSummary>> ParseSeries(std::string_view body) {
  ASSIGN_OR_RETURN(const json list, ParseList(body));
  std::vector<SeriesSummary> out;
  for (const json& item : list) {
    SeriesSummary s;
    s.series_uid = Text(item, "0020000E");
    if (!CheckUid(s.series_uid, "").ok()) continue;
    s.modality = Text(item, "00080060");
    s.description = Text(item, "0008103E");
    s.body_part = Text(item, "00180015");
    s.series_number = Number(item, "00200011", 0);
    s.instance_count = Number(item, "00201209", -1);
    out.push_back(std::move(s));
  }
  return out;
}

Result<std::vector<InstanceSummary>> ParseInstances(std::string_view body) {
  ASSIGN_OR_RETURN(const json list, ParseList(body));
  std::vector<InstanceSummary> out;
  for (const json& item : list) {
    InstanceSummary s;
    s.sop_uid = Text(item, "00080018");
    if (!CheckUid(s.sop_uid, "").ok()) continue;
    s.instance_number = Number(item, "00200013", 0);
    out.push_back(std::move(s));
  }
  return out;
}

const InstanceSummary* MiddleInstance(const std::vector<InstanceSummary>& instances) {
  if (instances.empty()) return nullptr;
  std::vector<const InstanceSummary*> sorted;
  for (const InstanceSummary& s : instances) sorted.push_back(&s);
  std::stable_sort(sorted.begin(), sorted.end(),
                   [](const InstanceSummary* a, const InstanceSummary* b) {
                     return a->instance_number < b->instance_number;
                   });
  return sorted[sorted.size() / 2];
}

}  // namespace vpm::pacs
