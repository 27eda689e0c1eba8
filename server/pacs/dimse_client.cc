#include "server/pacs/dimse_client.h"

#include <dcmtk/config/osconfig.h>  // first among DCMTK headers
#include <dcmtk/dcmdata/dcistrmb.h>
#include <dcmtk/dcmdata/dctk.h>
#include <dcmtk/dcmnet/diutil.h>
#include <dcmtk/dcmnet/scu.h>

#include <algorithm>
#include <cstdio>
#include <memory>
#include <set>
#include <utility>

#include "server/common/prefix_status.h"
#include "server/common/valid_utf8.h"
#include "server/io/dicom_text.h"

namespace vpm::pacs {
namespace {

std::string DimseLabel(const PacsEndpoint& e) {
  return StrCat(EndpointLabel(e), " (", e.dimse_ae_title, "@", e.dimse_host, ":", e.dimse_port,
                ")");
}

// What a refused or failed association or message means to the user.
Status FromCondition(const OFCondition& cond, const PacsEndpoint& e, const std::string& what) {
  const std::string head = StrCat(DimseLabel(e), ": ", what, ": ", cond.text());
  if (cond == DUL_ASSOCIATIONREJECTED) {
    return absl::PermissionDeniedError(StrCat(
        head, " (the PACS rejected the association: does it know vpm's AE title '",
        e.calling_ae_title, "' and its own, '", e.dimse_ae_title, "'?)"));
  }
  if (cond == DIMSE_NODATAAVAILABLE || cond == DUL_READTIMEOUT) {
    return absl::DeadlineExceededError(StrCat(head, " (the PACS stopped answering)"));
  }
  if (cond == NET_EC_NoAcceptablePresentationContexts || cond == DIMSE_NOVALIDPRESENTATIONCONTEXTID) {
    return absl::FailedPreconditionError(StrCat(head, " (the PACS does not offer this service)"));
  }
  return absl::UnavailableError(StrCat(head, " (is the PACS running and reachable?)"));
}

int64_t Number(DcmItem& ds, const DcmTagKey& key, int64_t absent) {
  const std::string text = DicomText(ds, key);
  return text.empty() ? absent : std::atoll(text.c_str());
}

// DcmSCU with vpm's limits: C-FIND answers counted (cancelled past a cap or
// when the caller gives up), C-STORE sub-operations of a C-GET written to a
// folder under a byte budget, one series only.
class Scu : public DcmSCU {
 public:
  const CancelToken* cancel = nullptr;
  int64_t find_cap = 0;
  int64_t find_answers = 0;
  bool find_cancelled = false;
  bool move_cancelled = false;
  // C-GET
  std::filesystem::path folder;
  std::string series_uid;
  int64_t max_bytes = 0, expected = 0;
  const ProgressFn* progress = nullptr;
  RetrievedSeries received;
  Status store_error;

 protected:
  OFCondition handleFINDResponse(const T_ASC_PresentationContextID id, QRResponse* response,
                                 OFBool& wait) override {
    const OFCondition cond = DcmSCU::handleFINDResponse(id, response, wait);
    if (response->m_dataset != nullptr) ++find_answers;
    if (wait && !find_cancelled && (find_answers > find_cap || !cancel->Check().ok())) {
      find_cancelled = true;
      sendCANCELRequest(id);  // the PACS ends the find with a Cancel status
    }
    return cond;
  }
  OFCondition handleMOVEResponse(const T_ASC_PresentationContextID id, RetrieveResponse* response,
                                 OFBool& wait) override {
    const OFCondition cond = DcmSCU::handleMOVEResponse(id, response, wait);
    if (wait && !move_cancelled && !cancel->Check().ok()) {
      move_cancelled = true;
      sendCANCELRequest(id);  // the PACS ends the move with a Cancel status
    }
    if (progress != nullptr && *progress && expected > 0) {
      (*progress)(std::min(1.0, double(response->m_numberOfCompletedSubops) / double(expected)),
                  "retrieving");
    }
    return cond;
  }
  OFCondition handleSTORERequest(const T_ASC_PresentationContextID, DcmDataset* incoming,
                                 OFBool& go_on, Uint16& status) override {
    std::unique_ptr<DcmDataset> owned(incoming);  // ours to delete
    store_error = Take(*owned);
    go_on = store_error.ok();
    status = store_error.ok() ? STATUS_Success : STATUS_STORE_Refused_OutOfResources;
    return EC_Normal;
  }

 private:
  Status Take(DcmDataset& ds) {
    RETURN_IF_ERROR(cancel->Check());
    if (DicomText(ds, DCM_SeriesInstanceUID) != series_uid) {
      return absl::InvalidArgumentError(
          StrCat("the PACS sent an instance of another series with series ", series_uid));
    }
    char name[32];
    std::snprintf(name, sizeof name, "%06lld.dcm", static_cast<long long>(received.instances + 1));
    const std::filesystem::path path = folder / name;
    DcmFileFormat file(&ds);
    const OFCondition saved = file.saveFile(path.c_str(), ds.getOriginalXfer());
    if (saved.bad()) return absl::InternalError(StrCat("cannot write a received instance: ", saved.text()));
    std::error_code error;
    received.bytes += static_cast<int64_t>(std::filesystem::file_size(path, error));
    ++received.instances;
    if (received.bytes > max_bytes) {
      return absl::ResourceExhaustedError(
          StrCat("series ", series_uid, " is over ", max_bytes, " bytes (--pacs-cache-bytes)"));
    }
    if (progress != nullptr && *progress && expected > 0) {
      (*progress)(std::min(1.0, double(received.instances) / double(expected)), "retrieving");
    }
    return absl::OkStatus();
  }
};

const OFList<OFString>& PlainSyntaxes() {
  static const OFList<OFString> list = [] {
    OFList<OFString> l;
    l.push_back(UID_LittleEndianExplicitTransferSyntax);
    l.push_back(UID_LittleEndianImplicitTransferSyntax);
    return l;
  }();
  return list;
}

// What a C-GET accepts for the images it receives, in two contexts per
// storage class: uncompressed, and compressed (JPEG 2000, JPEG, JPEG-LS,
// RLE): the PACS sends each instance as stored where it can, decompressing
// only what matches neither; the readers decode them all.
const OFList<OFString>& CompressedSyntaxes() {
  static const OFList<OFString> list = [] {
    OFList<OFString> l;
    for (const char* uid :
         {UID_JPEG2000LosslessOnlyTransferSyntax, UID_JPEG2000TransferSyntax,
          UID_JPEGProcess14SV1TransferSyntax, UID_JPEGProcess1TransferSyntax,
          UID_JPEGLSLosslessTransferSyntax, UID_RLELosslessTransferSyntax}) {
      l.push_back(uid);
    }
    return l;
  }();
  return list;
}

// A new association with the endpoint for `contexts` (abstract syntax,
// transfer syntaxes, our role).
struct Context {
  const char* abstract_syntax;
  const OFList<OFString>* syntaxes;
  T_ASC_SC_ROLE role;
};
Result<std::unique_ptr<Scu>> Associate(const PacsEndpoint& e, const DimseClient::Options& o,
                                       const std::vector<Context>& contexts,
                                       const CancelToken& cancel, const std::string& what) {
  RETURN_IF_ERROR(cancel.Check());
  auto scu = std::make_unique<Scu>();
  scu->cancel = &cancel;
  scu->setAETitle(e.calling_ae_title.c_str());
  scu->setPeerHostName(e.dimse_host.c_str());
  scu->setPeerPort(static_cast<Uint16>(e.dimse_port));
  scu->setPeerAETitle(e.dimse_ae_title.c_str());
  scu->setACSETimeout(static_cast<Uint32>(o.connect_timeout_s));
  scu->setConnectionTimeout(static_cast<Sint32>(o.connect_timeout_s));
  scu->setDIMSEBlockingMode(DIMSE_NONBLOCKING);
  scu->setDIMSETimeout(static_cast<Uint32>(o.dimse_timeout_s));
  scu->setVerbosePCMode(OFFalse);
  for (const Context& c : contexts) {
    const OFCondition added = scu->addPresentationContext(c.abstract_syntax, *c.syntaxes, c.role);
    if (added.bad()) return FromCondition(added, e, what);
  }
  if (OFCondition c = scu->initNetwork(); c.bad()) return FromCondition(c, e, what);
  if (OFCondition c = scu->negotiateAssociation(); c.bad()) return FromCondition(c, e, what);
  return scu;
}

void Release(Scu& scu) {
  if (scu.isConnected()) scu.releaseAssociation();
}

// The final status of a C-FIND, C-GET or C-STORE (0: success; Cancel after
// our cancel; warnings B000-BFFF accepted by the caller).
Status FromDimseStatus(Uint16 status, const PacsEndpoint& e, const std::string& what) {
  if (status == STATUS_Success || status == STATUS_Pending || status == 0xFF01) {
    return absl::OkStatus();
  }
  char code[8];
  std::snprintf(code, sizeof code, "%04X", status);
  const std::string head = StrCat(DimseLabel(e), ": ", what, ": status ", code);
  if ((status & 0xFF00) == 0xA700) {
    return absl::UnavailableError(StrCat(head, " (the PACS is out of resources; try again later)"));
  }
  if (status == 0xA801) {
    return absl::FailedPreconditionError(StrCat(head, " (the PACS does not know vpm's AE title as a destination)"));
  }
  if ((status & 0xF000) == 0xA000 || (status & 0xF000) == 0xC000) {
    return absl::UnavailableError(StrCat(head, " (the PACS failed to process the request)"));
  }
  return absl::UnavailableError(StrCat(head, " (an answer vpm does not expect)"));
}

StudySummary StudyFromAnswer(DcmDataset& ds) {
  ConvertDicomTextToUtf8(ds);
  StudySummary s;
  s.study_uid = DicomText(ds, DCM_StudyInstanceUID);
  s.patient_name = DicomText(ds, DCM_PatientName);
  s.patient_id = DicomText(ds, DCM_PatientID);
  s.patient_birth_date = DicomText(ds, DCM_PatientBirthDate);
  s.study_date = DicomText(ds, DCM_StudyDate);
  s.study_description = DicomText(ds, DCM_StudyDescription);
  s.accession_number = DicomText(ds, DCM_AccessionNumber);
  const std::string modalities = DicomText(ds, DCM_ModalitiesInStudy);
  for (size_t at = 0; at < modalities.size();) {
    const size_t end = std::min(modalities.find('\\', at), modalities.size());
    if (end > at) s.modalities.push_back(modalities.substr(at, end - at));
    at = end + 1;
  }
  s.series_count = Number(ds, DCM_NumberOfStudyRelatedSeries, -1);
  s.instance_count = Number(ds, DCM_NumberOfStudyRelatedInstances, -1);
  return s;
}

SeriesSummary SeriesFromAnswer(DcmDataset& ds) {
  ConvertDicomTextToUtf8(ds);
  return {.series_uid = DicomText(ds, DCM_SeriesInstanceUID),
          .modality = DicomText(ds, DCM_Modality),
          .description = DicomText(ds, DCM_SeriesDescription),
          .body_part = DicomText(ds, DCM_BodyPartExamined),
          .series_number = Number(ds, DCM_SeriesNumber, 0),
          .instance_count = Number(ds, DCM_NumberOfSeriesRelatedInstances, -1)};
}

// One C-FIND of `keys`; the answers' datasets, and whether it was cut short.
Result<std::vector<std::unique_ptr<DcmDataset>>> Find(const PacsEndpoint& e,
                                                     const DimseClient::Options& o,
                                                     DcmDataset& keys, int64_t cap,
                                                     const CancelToken& cancel, bool* cut) {
  const std::string what = "C-FIND";
  ASSIGN_OR_RETURN(std::unique_ptr<Scu> scu,
                   Associate(e, o,
                             {{UID_FINDStudyRootQueryRetrieveInformationModel, &PlainSyntaxes(),
                               ASC_SC_ROLE_DEFAULT}},
                             cancel, what));
  scu->find_cap = cap;
  const T_ASC_PresentationContextID id =
      scu->findPresentationContextID(UID_FINDStudyRootQueryRetrieveInformationModel, "");
  OFList<QRResponse*> responses;
  const OFCondition sent = scu->sendFINDRequest(id, &keys, &responses);
  std::vector<std::unique_ptr<DcmDataset>> answers;
  Uint16 final_status = STATUS_Success;
  for (QRResponse* r : responses) {
    if (r->m_dataset != nullptr && r->m_status != STATUS_Success) {
      answers.emplace_back(r->m_dataset);
      r->m_dataset = nullptr;
    }
    final_status = r->m_status;
    delete r;
  }
  *cut = scu->find_cancelled;
  Release(*scu);
  RETURN_IF_ERROR(cancel.Check());
  if (sent.bad()) return FromCondition(sent, e, what);
  if (!scu->find_cancelled) RETURN_IF_ERROR(FromDimseStatus(final_status, e, what));
  return answers;
}

// The identifier of a C-GET or C-MOVE: the series, or its instance
// `sop_uid` when not empty.
void RetrieveKeys(const std::string& study_uid, const std::string& series_uid,
                  const std::string& sop_uid, DcmDataset& keys) {
  keys.putAndInsertString(DCM_QueryRetrieveLevel, sop_uid.empty() ? "SERIES" : "IMAGE");
  keys.putAndInsertString(DCM_StudyInstanceUID, study_uid.c_str());
  keys.putAndInsertString(DCM_SeriesInstanceUID, series_uid.c_str());
  if (!sop_uid.empty()) keys.putAndInsertString(DCM_SOPInstanceUID, sop_uid.c_str());
}

}  // namespace

DimseClient::DimseClient(PacsEndpoint endpoint, Options options, MoveRegistry* moves)
    : endpoint_(std::move(endpoint)), options_(options), moves_(moves) {}

Status DimseClient::Echo(const CancelToken& cancel) const {
  ASSIGN_OR_RETURN(std::unique_ptr<Scu> scu,
                   Associate(endpoint_, options_,
                             {{UID_VerificationSOPClass, &PlainSyntaxes(), ASC_SC_ROLE_DEFAULT}},
                             cancel, "C-ECHO"));
  const OFCondition echoed = scu->sendECHORequest(0);
  Release(*scu);
  return echoed.good() ? absl::OkStatus() : FromCondition(echoed, endpoint_, "C-ECHO");
}

Result<StudySearch> DimseClient::SearchStudies(const StudyQuery& query,
                                               const CancelToken& cancel) const {
  RETURN_IF_ERROR(CheckStudyQuery(query));
  DcmDataset keys;
  keys.putAndInsertString(DCM_QueryRetrieveLevel, "STUDY");
  for (const auto& [key, value] :
       std::vector<std::pair<DcmTagKey, std::string>>{
           {DCM_StudyInstanceUID, ""},
           {DCM_PatientName, query.patient_name},
           {DCM_PatientID, query.patient_id},
           {DCM_PatientBirthDate, query.patient_birth_date},
           {DCM_StudyDate, query.study_date},
           {DCM_StudyDescription, ""},
           {DCM_AccessionNumber, query.accession_number},
           {DCM_ModalitiesInStudy, query.modality},
           {DCM_NumberOfStudyRelatedSeries, ""},
           {DCM_NumberOfStudyRelatedInstances, ""}}) {
    keys.putAndInsertString(key, value.c_str());
  }
  // The keys are UTF-8 (they came through the API): a name beyond ASCII
  // ("M\xc3\xbcller*") is matched only where the PACS knows their set.
  if (!IsAscii(query.patient_name) || !IsAscii(query.patient_id) ||
      !IsAscii(query.accession_number)) {
    keys.putAndInsertString(DCM_SpecificCharacterSet, "ISO_IR 192");
  }
  bool cut = false;
  ASSIGN_OR_RETURN(const std::vector<std::unique_ptr<DcmDataset>> answers,
                   Find(endpoint_, options_, keys, std::min(query.limit, options_.max_find_answers),
                        cancel, &cut));
  StudySearch out{.requests = 1};
  std::set<std::string> seen;
  for (const auto& answer : answers) {
    StudySummary s = StudyFromAnswer(*answer);
    if (!CheckUid(s.study_uid, "StudyInstanceUID").ok() || !seen.insert(s.study_uid).second) continue;
    if (static_cast<int64_t>(out.studies.size()) == query.limit) {
      out.truncated = true;
      break;
    }
    out.studies.push_back(std::move(s));
  }
  out.truncated = out.truncated || cut;
  return out;
}

Result<std::vector<SeriesSummary>> DimseClient::ListSeries(const std::string& study_uid,
                                                           const CancelToken& cancel) const {
  RETURN_IF_ERROR(CheckUid(study_uid, "study_uid"));
  DcmDataset keys;
  keys.putAndInsertString(DCM_QueryRetrieveLevel, "SERIES");
  keys.putAndInsertString(DCM_StudyInstanceUID, study_uid.c_str());
  for (const DcmTagKey& key : {DCM_SeriesInstanceUID, DCM_Modality, DCM_SeriesDescription,
                               DCM_BodyPartExamined, DCM_SeriesNumber,
                               DCM_NumberOfSeriesRelatedInstances}) {
    keys.putAndInsertString(key, "");
  }
  bool cut = false;
  ASSIGN_OR_RETURN(const std::vector<std::unique_ptr<DcmDataset>> answers,
                   Find(endpoint_, options_, keys, options_.max_find_answers, cancel, &cut));
  std::vector<SeriesSummary> out;
  for (const auto& answer : answers) {
    SeriesSummary s = SeriesFromAnswer(*answer);
    if (CheckUid(s.series_uid, "SeriesInstanceUID").ok()) out.push_back(std::move(s));
  }
  std::stable_sort(out.begin(), out.end(), [](const SeriesSummary& a, const SeriesSummary& b) {
    return a.series_number < b.series_number;
  });
  return out;
}

Result<RetrievedSeries> DimseClient::RetrieveSeries(const std::string& study_uid,
                                                    const std::string& series_uid,
                                                    const std::filesystem::path& folder,
                                                    int64_t max_bytes, int64_t expected_instances,
                                                    const ProgressFn& progress,
                                                    const CancelToken& cancel) const {
  RETURN_IF_ERROR(CheckUid(study_uid, "study_uid"));
  RETURN_IF_ERROR(CheckUid(series_uid, "series_uid"));
  if (endpoint_.retrieve_by_move) {
    return MoveSeries(study_uid, series_uid, "", folder, max_bytes, expected_instances, progress,
                      cancel);
  }
  return GetSeries(study_uid, series_uid, "", folder, max_bytes, expected_instances, progress,
                   cancel);
}

Result<RetrievedSeries> DimseClient::RetrieveInstance(const std::string& study_uid,
                                                      const std::string& series_uid,
                                                      const std::filesystem::path& folder,
                                                      int64_t max_bytes,
                                                      const CancelToken& cancel) const {
  RETURN_IF_ERROR(CheckUid(study_uid, "study_uid"));
  RETURN_IF_ERROR(CheckUid(series_uid, "series_uid"));
  DcmDataset keys;
  keys.putAndInsertString(DCM_QueryRetrieveLevel, "IMAGE");
  keys.putAndInsertString(DCM_StudyInstanceUID, study_uid.c_str());
  keys.putAndInsertString(DCM_SeriesInstanceUID, series_uid.c_str());
  keys.putAndInsertString(DCM_SOPInstanceUID, "");
  keys.putAndInsertString(DCM_InstanceNumber, "");
  bool cut = false;
  ASSIGN_OR_RETURN(const std::vector<std::unique_ptr<DcmDataset>> answers,
                   Find(endpoint_, options_, keys, options_.max_find_answers, cancel, &cut));
  std::vector<InstanceSummary> instances;
  for (const auto& answer : answers) {
    InstanceSummary s{.sop_uid = DicomText(*answer, DCM_SOPInstanceUID),
                      .instance_number = Number(*answer, DCM_InstanceNumber, 0)};
    if (CheckUid(s.sop_uid, "").ok()) instances.push_back(std::move(s));
  }
  const InstanceSummary* middle = MiddleInstance(instances);
  if (middle == nullptr) {
    return absl::NotFoundError(
        StrCat(DimseLabel(endpoint_), ": series ", series_uid, ": the PACS lists no instance"));
  }
  if (endpoint_.retrieve_by_move) {
    return MoveSeries(study_uid, series_uid, middle->sop_uid, folder, max_bytes, 1, nullptr,
                      cancel);
  }
  return GetSeries(study_uid, series_uid, middle->sop_uid, folder, max_bytes, 1, nullptr, cancel);
}

Result<RetrievedSeries> DimseClient::GetSeries(const std::string& study_uid,
                                               const std::string& series_uid,
                                               const std::string& sop_uid,
                                               const std::filesystem::path& folder,
                                               int64_t max_bytes, int64_t expected_instances,
                                               const ProgressFn& progress,
                                               const CancelToken& cancel) const {
  std::vector<Context> contexts = {
      {UID_GETStudyRootQueryRetrieveInformationModel, &PlainSyntaxes(), ASC_SC_ROLE_DEFAULT}};
  // The storage classes a C-GET may bring, vpm taking the SCP role (at
  // most 127 contexts in all).
  for (int n = 0; n < numberOfDcmShortSCUStorageSOPClassUIDs && contexts.size() < 126; ++n) {
    contexts.push_back({dcmShortSCUStorageSOPClassUIDs[n], &PlainSyntaxes(), ASC_SC_ROLE_SCP});
    contexts.push_back({dcmShortSCUStorageSOPClassUIDs[n], &CompressedSyntaxes(), ASC_SC_ROLE_SCP});
  }
  ASSIGN_OR_RETURN(std::unique_ptr<Scu> scu,
                   Associate(endpoint_, options_, contexts, cancel, "C-GET"));
  scu->folder = folder;
  scu->series_uid = series_uid;
  scu->max_bytes = max_bytes;
  scu->expected = expected_instances;
  scu->progress = &progress;
  DcmDataset keys;
  RetrieveKeys(study_uid, series_uid, sop_uid, keys);
  const T_ASC_PresentationContextID id =
      scu->findPresentationContextID(UID_GETStudyRootQueryRetrieveInformationModel, "");
  OFList<RetrieveResponse*> responses;
  const OFCondition sent = scu->sendCGETRequest(id, &keys, &responses);
  Uint16 final_status = STATUS_Success;
  for (RetrieveResponse* r : responses) {
    final_status = r->m_status;
    delete r;
  }
  Release(*scu);
  RETURN_IF_ERROR(scu->store_error);
  RETURN_IF_ERROR(cancel.Check());
  if (sent.bad()) return FromCondition(sent, endpoint_, "C-GET");
  // B000: some sub-operations failed; what arrived is checked by the caller.
  if ((final_status & 0xF000) != 0xB000) {
    RETURN_IF_ERROR(FromDimseStatus(final_status, endpoint_, "C-GET"));
  }
  if (scu->received.instances == 0) {
    return absl::NotFoundError(StrCat(DimseLabel(endpoint_), ": C-GET of series ", series_uid,
                                      " brought nothing (no such series on the PACS?)"));
  }
  return scu->received;
}

Result<RetrievedSeries> DimseClient::MoveSeries(const std::string& study_uid,
                                                const std::string& series_uid,
                                                const std::string& sop_uid,
                                                const std::filesystem::path& folder,
                                                int64_t max_bytes, int64_t expected_instances,
                                                const ProgressFn& progress,
                                                const CancelToken& cancel) const {
  if (moves_ == nullptr) {
    return absl::FailedPreconditionError(StrCat(
        DimseLabel(endpoint_), ": \"retrieve\": \"move\" needs vpm-server --dicom-listen"));
  }
  ASSIGN_OR_RETURN(std::unique_ptr<MoveRegistry::Expectation> expected,
                   moves_->Expect(series_uid, endpoint_.dimse_ae_title,
                                  endpoint_.calling_ae_title, folder, max_bytes));
  ASSIGN_OR_RETURN(std::unique_ptr<Scu> scu,
                   Associate(endpoint_, options_,
                             {{UID_MOVEStudyRootQueryRetrieveInformationModel, &PlainSyntaxes(),
                               ASC_SC_ROLE_DEFAULT}},
                             cancel, "C-MOVE"));
  scu->expected = expected_instances;
  scu->progress = &progress;
  DcmDataset keys;
  RetrieveKeys(study_uid, series_uid, sop_uid, keys);
  const T_ASC_PresentationContextID id =
      scu->findPresentationContextID(UID_MOVEStudyRootQueryRetrieveInformationModel, "");
  OFList<RetrieveResponse*> responses;
  const OFCondition sent =
      scu->sendMOVERequest(id, endpoint_.move_destination.c_str(), &keys, &responses);
  Uint16 final_status = STATUS_Success;
  int64_t completed = 0;
  for (RetrieveResponse* r : responses) {
    final_status = r->m_status;
    completed = r->m_numberOfCompletedSubops;
    delete r;
  }
  Release(*scu);
  RETURN_IF_ERROR(cancel.Check());
  if (sent.bad()) return FromCondition(sent, endpoint_, "C-MOVE");
  RETURN_IF_ERROR(expected->failure());
  if ((final_status & 0xF000) != 0xB000) {
    RETURN_IF_ERROR(FromDimseStatus(final_status, endpoint_, "C-MOVE"));
  }
  // The PACS answers once it has sent them; the listener may still be
  // writing the last ones.
  Status landed = expected->WaitFor(completed, cancel, options_.move_arrival_s);
  if (!landed.ok()) return PrefixStatus(landed, StrCat(DimseLabel(endpoint_), ": C-MOVE"));
  if (expected->instances() == 0) {
    return absl::NotFoundError(StrCat(DimseLabel(endpoint_), ": C-MOVE of series ", series_uid,
                                      " brought nothing (no such series on the PACS?)"));
  }
  return RetrievedSeries{.instances = expected->instances(), .bytes = expected->bytes()};
}

Status DimseClient::Store(const std::vector<const std::string*>& files,
                          const ProgressFn& progress, const CancelToken& cancel) const {
  ASSIGN_OR_RETURN(std::unique_ptr<Scu> scu,
                   Associate(endpoint_, options_,
                             {{UID_CTImageStorage, &PlainSyntaxes(), ASC_SC_ROLE_DEFAULT},
                              {UID_MRImageStorage, &PlainSyntaxes(), ASC_SC_ROLE_DEFAULT},
                              {UID_SecondaryCaptureImageStorage, &PlainSyntaxes(),
                               ASC_SC_ROLE_DEFAULT}},
                             cancel, "C-STORE"));
  int64_t refused = 0;
  Status failure;
  for (size_t n = 0; n < files.size() && failure.ok(); ++n) {
    failure = cancel.Check();
    if (!failure.ok()) break;
    DcmInputBufferStream in;
    in.setBuffer(files[n]->data(), static_cast<offile_off_t>(files[n]->size()));
    in.setEos();
    DcmFileFormat file;
    file.transferInit();
    const OFCondition read = file.read(in);
    file.transferEnd();
    if (read.bad()) {
      failure = absl::InternalError(StrCat("an exported file does not parse: ", read.text()));
      break;
    }
    Uint16 status = 0;
    const OFCondition sent = scu->sendSTORERequest(0, "", file.getDataset(), status);
    if (sent.bad()) failure = FromCondition(sent, endpoint_, "C-STORE");
    if (sent.good() && status != STATUS_Success && (status & 0xF000) != 0xB000) ++refused;
    if (progress) progress(double(n + 1) / double(files.size()), "sending");
  }
  Release(*scu);
  RETURN_IF_ERROR(failure);
  if (refused > 0) {
    return absl::FailedPreconditionError(StrCat(DimseLabel(endpoint_), ": the PACS refused ",
                                                refused, " of ", files.size(), " instances"));
  }
  return absl::OkStatus();
}

}  // namespace vpm::pacs
