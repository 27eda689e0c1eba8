#include "server/pacs/store_association.h"

#include <sys/socket.h>

#include <cstdio>
#include <filesystem>

#include "server/pacs/received_instance.h"

namespace vpm::pacs {
namespace {

namespace fs = std::filesystem;

// DIMSE C-STORE statuses (PS3.4 B.2.3).
constexpr Uint16 kStoreOutOfResources = 0xA700;
constexpr Uint16 kStoreSopClassNotSupported = 0x0122;
constexpr Uint16 kStoreCannotUnderstand = 0xC000;
constexpr Uint16 kStoreNotAuthorized = 0x0124;

std::string AeText(const char* text) {
  std::string ae(text);
  while (!ae.empty() && ae.back() == ' ') ae.pop_back();
  while (!ae.empty() && ae.front() == ' ') ae.erase(ae.begin());
  return ae;
}

}  // namespace

StoreAssociation::StoreAssociation(Context context, int socket)
    : context_(std::move(context)), socket_(socket) {}

OFBool StoreAssociation::checkCalledAETitleAccepted(const OFString& called_ae) {
  return AeText(called_ae.c_str()) == context_.ae_title;
}

void StoreAssociation::notifyAssociationRequest(const T_ASC_Parameters& params,
                                                DcmSCPActionType& action) {
  calling_ae_ = AeText(params.DULparams.callingAPTitle);
  // DCMTK 3.6.7 listens on every interface: a loopback --dicom-listen HOST
  // refuses peers from elsewhere.
  const std::string peer = params.DULparams.callingPresentationAddress;
  if (context_.loopback_only && !peer.starts_with("127.") && !peer.starts_with("localhost")) {
    action = DCMSCP_ACTION_REFUSE_ASSOCIATION;
  }
}

void StoreAssociation::notifyRECEIVEProgress(unsigned long bytes) {
  // An instance over the cap ends the association: its bytes are not
  // written on (the sender sees the association cut).
  if (static_cast<int64_t>(bytes) > context_.max_instance_bytes && !over_cap_) {
    over_cap_ = true;
    ::shutdown(socket_, SHUT_RDWR);
  }
}

OFCondition StoreAssociation::handleIncomingCommand(T_DIMSE_Message* message,
                                                    const DcmPresentationContextInfo& context) {
  if (message->CommandField != DIMSE_C_STORE_RQ) {
    return DcmThreadSCP::handleIncomingCommand(message, context);
  }
  T_DIMSE_C_StoreRQ& request = message->msg.CStoreRQ;
  if (!incoming_) {
    Result<std::unique_ptr<ReceivedStore::Incoming>> made = context_.store->BeginIncoming();
    if (!made.ok()) return DIMSE_BADCOMMANDTYPE;
    incoming_ = std::move(*made);
  }
  char name[32];
  std::snprintf(name, sizeof name, "r%06lld.dcm", static_cast<long long>(++received_));
  const std::string path = (incoming_->folder() / name).string();
  const OFCondition received =
      receiveSTORERequest(request, context.presentationContextID, OFString(path.c_str()));
  if (received.bad()) {
    std::error_code error;
    fs::remove(path, error);
    return received;  // the association ends (cut, aborted, over the cap)
  }
  const Uint16 status = Keep(path, request);
  return sendSTOREResponse(context.presentationContextID, request, status);
}

Uint16 StoreAssociation::Keep(const std::string& path, const T_DIMSE_C_StoreRQ& request) {
  std::error_code error;
  const int64_t bytes = static_cast<int64_t>(fs::file_size(path, error));
  Result<ReceivedInstance> instance = ReadReceivedInstance(path);
  if (error || bytes > context_.max_instance_bytes || !instance.ok() || !instance->has_image) {
    fs::remove(path, error);
    if (!instance.ok()) return kStoreCannotUnderstand;
    SeriesState& state = series_[instance->series_uid];
    state.files.attributes = *instance;
    ++state.refused;
    if (bytes > context_.max_instance_bytes) {
      state.failure = absl::ResourceExhaustedError("an instance over --dicom-max-instance-bytes");
      return kStoreOutOfResources;
    }
    if (state.failure.ok()) {
      state.failure = absl::FailedPreconditionError(
          "holds no image (a structured report, a dose report or a presentation state)");
    }
    return kStoreSopClassNotSupported;
  }
  const std::string originator = (request.opts & O_STORE_MOVEORIGINATORAETITLE) != 0
                                     ? AeText(request.MoveOriginatorApplicationEntityTitle)
                                     : std::string();
  if (context_.moves != nullptr) {
    if (std::shared_ptr<MoveRegistry::Sink> sink =
            context_.moves->Route(instance->series_uid, calling_ae_, originator)) {
      const Status kept = sink->Keep(path, bytes);
      if (kept.ok()) return STATUS_Success;
      fs::remove(path, error);
      return kStoreOutOfResources;
    }
  }
  if (context_.own_move_originators.contains(originator)) {
    fs::remove(path, error);
    return kStoreNotAuthorized;
  }
  return KeepForStore(path, bytes, *instance);
}

Uint16 StoreAssociation::KeepForStore(const std::string& path, int64_t bytes,
                                      const ReceivedInstance& instance) {
  SeriesState& state = series_[instance.series_uid];
  if (state.files.files.empty()) {
    state.files.attributes = instance;
    state.files.calling_ae = calling_ae_;
  }
  std::error_code error;
  Status reserved = state.failure.ok() ? context_.store->Reserve(bytes) : state.failure;
  if (!reserved.ok()) {
    // The series would be partial: nothing of it is kept.
    if (state.failure.ok()) state.failure = reserved;
    ++state.refused;
    fs::remove(path, error);
    return kStoreOutOfResources;
  }
  state.files.files.emplace_back(path, instance.sop_uid);
  state.files.bytes += bytes;
  return STATUS_Success;
}

void StoreAssociation::notifyAssociationTermination() {
  for (auto& [uid, state] : series_) {
    ReceiveReport report{.calling_ae = calling_ae_,
                         .study_uid = state.files.attributes.study_uid,
                         .series_uid = uid,
                         .refused = state.refused};
    if (state.failure.ok() && !released_) {
      state.failure = absl::AbortedError("the association ended without a release");
    }
    if (state.failure.ok() && state.files.files.empty()) continue;  // all went to a C-MOVE
    if (!state.failure.ok()) {
      context_.store->Release(state.files.bytes);
      report.result = state.failure;
    } else {
      Result<int64_t> added = context_.store->Commit(state.files);
      report.result = added.status();
      report.instances = added.ok() ? static_cast<int64_t>(state.files.files.size()) : 0;
      if (!added.ok()) context_.store->Release(state.files.bytes);
    }
    if (context_.report) context_.report(report);
  }
  series_.clear();
  incoming_.reset();
  if (context_.on_end) context_.on_end();
}

}  // namespace vpm::pacs
