// The case RPCs of VpmService (docs/CASES.md): list, read, open (load,
// build, replay), rename, share, delete, undo and redo, over the case store
// of --state-dir. Another user's case answers as a missing one.
#include <filesystem>

#include "server/common/random_hex.h"
#include "server/scene/scene_history.h"
#include "server/service/case_archive.h"
#include "server/service/case_view.h"
#include "server/service/vpm_service.h"

namespace vpm::service {
namespace {

constexpr size_t kMaxTitleBytes = 256;

Result<cases::CaseStore*> Cases(ServiceContext* service) {
  if (service->cases == nullptr) {
    return absl::FailedPreconditionError(
        "this server keeps no cases (start vpm-server with --state-dir DIR)");
  }
  return service->cases;
}

Status CaseNotFound(std::string_view id) {
  return absl::NotFoundError(StrCat("case '", id, "' not found"));
}

// Releases a case's place in opening_cases_ when the open ends.
class OpeningCase {
 public:
  OpeningCase(std::mutex& mutex, std::set<std::string>& opening, std::string id)
      : mutex_(mutex), opening_(opening), id_(std::move(id)) {
    std::lock_guard lock(mutex_);
    held_ = opening_.insert(id_).second;
  }
  ~OpeningCase() {
    if (!held_) return;
    std::lock_guard lock(mutex_);
    opening_.erase(id_);
  }
  OpeningCase(const OpeningCase&) = delete;
  OpeningCase& operator=(const OpeningCase&) = delete;
  bool held() const { return held_; }

 private:
  std::mutex& mutex_;
  std::set<std::string>& opening_;
  std::string id_;
  bool held_ = false;
};

// An archive's view as a case stores it ("" when it has none), checked on
// its volume as a client's settings would be: InvalidArgument naming
// "archive.view".
Result<std::string> ArchivedView(const v3::CaseArchive& archive, const Volume& volume,
                                 int max_side) {
  if (!archive.has_view()) return std::string();
  const v3::RenderSettings view = CaseView(archive.view());
  RETURN_IF_ERROR(CheckCaseViewSize(view, "archive.view"));
  if (Result<StreamSettings> checked = ToStreamSettings(view, volume, max_side); !checked.ok()) {
    return absl::InvalidArgumentError(StrCat("archive.view: ", checked.status().message()));
  }
  return view.SerializeAsString();
}

}  // namespace

Result<std::shared_ptr<VolumeEntry>> VpmService::LoadCaseVolume(const cases::CaseRecord& record,
                                                                const std::string& user,
                                                                const CancelToken& cancel) {
  if (!record.source.starts_with("upload:")) {
    return service_->volumes->Load(record.source, user, {}, cancel);
  }
  const auto blob = cases::BlobStore::ParseReference(record.source);
  const auto path = blob && service_->blobs ? service_->blobs->Find(blob->first, blob->second)
                                            : std::nullopt;
  if (!path) {
    return absl::FailedPreconditionError(
        StrCat("case '", record.id, "': its volume was an upload this server does not keep; "
               "upload it again and open a new session"));
  }
  ASSIGN_OR_RETURN(std::shared_ptr<VolumeEntry> volume,
                   service_->volumes->AddFile(*path, StrCat("upload:", blob->second), user));
  volume->upload_ref = record.source;
  return volume;
}

Status VpmService::ForgetKeptUpload(const std::string& source) {
  const auto blob = cases::BlobStore::ParseReference(source);
  if (!blob || service_->blobs == nullptr) return absl::OkStatus();
  ASSIGN_OR_RETURN(const int64_t others, service_->cases->CountWithSource(source));
  if (others > 0) return absl::OkStatus();
  return service_->blobs->Remove(blob->first, blob->second);
}

Status VpmService::StartCase(Session& session, const std::string& user) {
  if (service_->cases == nullptr) return absl::OkStatus();
  const VolumeEntry& volume = session.volume();
  std::string source = service_->volumes->ReloadSource(volume);
  if (source.empty()) source = StrCat("upload:", volume.id);
  cases::CaseRecord record;
  record.id = StrCat("case-", RandomHex(16));
  record.owner = user;
  record.title = std::filesystem::path(source).filename().string();
  record.source = source;
  record.mesh_params =
      MeshParamsToApi(session.mesh()->params, volume.volume.geometry()).SerializeAsString();
  RETURN_IF_ERROR(service_->cases->Create(record));
  return session.AttachCase(service_->cases, record.id, {}, "");
}

Result<cases::CaseRecord> VpmService::FindCase(const std::string& id, const std::string& user,
                                               bool owner_only) const {
  ASSIGN_OR_RETURN(cases::CaseStore * store, Cases(service_));
  Result<cases::CaseRecord> record = store->Get(id);
  if (absl::IsNotFound(record.status())) return CaseNotFound(id);
  RETURN_IF_ERROR(record.status());
  if (record->owner == user) return record;
  if (!owner_only && std::find(record->shared_with.begin(), record->shared_with.end(), user) !=
                         record->shared_with.end()) {
    return record;
  }
  return CaseNotFound(id);
}

std::shared_ptr<Session> VpmService::OpenSessionOf(const std::string& id,
                                                   const std::string& owner) const {
  for (const auto& session : service_->sessions->List(owner)) {
    if (session->case_id() == id && session->access().IsOwner(owner) && !session->closed()) {
      return session;
    }
  }
  return nullptr;
}

void VpmService::FillCaseInfo(const cases::CaseRecord& r, const std::string& user,
                              v3::CaseInfo* info) const {
  info->set_case_id(r.id);
  info->set_title(r.title);
  info->set_notes(r.notes);
  info->set_owner(r.owner);
  if (r.owner == user) {
    for (const std::string& u : r.shared_with) info->add_shared_with(u);
  }
  info->set_source(r.source);
  info->set_events(r.events);
  info->set_undone(r.undone);
  info->set_max_displacement_mm(r.max_displacement_mm);
  info->set_created_unix_ms(r.created_ms);
  info->set_modified_unix_ms(r.modified_ms);
  if (auto session = OpenSessionOf(r.id, r.owner)) info->set_session_id(session->id());
  info->mutable_mesh_params()->ParseFromString(r.mesh_params);
  if (!r.camera.empty()) info->mutable_camera()->ParseFromString(r.camera);
  if (!r.render_settings.empty()) info->mutable_view()->ParseFromString(r.render_settings);
}

grpc::ServerUnaryReactor* VpmService::ListCases(grpc::CallbackServerContext* context,
                                                const v3::ListCasesRequest*,
                                                v3::ListCasesResponse* response) {
  return Unary(context, "ListCases", service_->request_pool,
               [=, this](const std::string& user) -> Status {
    ASSIGN_OR_RETURN(cases::CaseStore * store, Cases(service_));
    ASSIGN_OR_RETURN(const std::vector<cases::CaseRecord> records, store->List(user));
    for (const cases::CaseRecord& r : records) FillCaseInfo(r, user, response->add_cases());
    return absl::OkStatus();
  });
}

grpc::ServerUnaryReactor* VpmService::GetCase(grpc::CallbackServerContext* context,
                                              const v3::GetCaseRequest* request,
                                              v3::CaseInfo* response) {
  return Unary(context, *request, "GetCase", service_->request_pool,
               [=, this](const std::string& user) -> Status {
    ASSIGN_OR_RETURN(const cases::CaseRecord record, FindCase(request->case_id(), user, false));
    FillCaseInfo(record, user, response);
    return absl::OkStatus();
  });
}

grpc::ServerUnaryReactor* VpmService::OpenCase(grpc::CallbackServerContext* context,
                                               const v3::OpenCaseRequest* request,
                                               v3::SessionInfo* response) {
  return Unary(context, *request, "OpenCase", service_->request_pool,
               [=, this](const std::string& user, const CancelToken& cancel) -> Status {
    RETURN_IF_ERROR(service_->AcceptingNewWork());
    ASSIGN_OR_RETURN(const cases::CaseRecord record, FindCase(request->case_id(), user, true));
    OpeningCase opening(opening_mutex_, opening_cases_, record.id);
    if (!opening.held()) {
      return absl::UnavailableError(
          StrCat("case '", record.id, "' is being opened by another call; retry"));
    }
    if (auto open = OpenSessionOf(record.id, user)) {
      FillSessionInfo(*open, user, response);
      return absl::OkStatus();
    }
    ASSIGN_OR_RETURN(std::shared_ptr<VolumeEntry> volume, LoadCaseVolume(record, user, cancel));
    v3::MeshParams api_params;
    if (!api_params.ParseFromString(record.mesh_params)) {
      return absl::DataLossError(StrCat("case '", record.id, "': its mesh parameters are unreadable"));
    }
    ASSIGN_OR_RETURN(MeshParams params, ToMeshParams(api_params, volume->volume.geometry()));
    ASSIGN_OR_RETURN(std::shared_ptr<const MeshEntry> mesh,
                     service_->meshes->Build(volume, params, cancel));
    RETURN_IF_ERROR(cancel.Check());
    ASSIGN_OR_RETURN(VolumeHold hold, service_->volumes->HoldForSession(mesh->volume, user));
    ASSIGN_OR_RETURN(std::shared_ptr<Session> session,
                     service_->sessions->Open(user, std::move(hold), mesh));
    Status attached = cancel.Check();
    if (attached.ok()) {
      Result<std::vector<cases::CaseEvent>> events = service_->cases->Events(record.id);
      attached = events.status();
      if (attached.ok()) {
        attached = session->AttachCase(service_->cases, record.id,
                                       SinceLastReset(cases::ReplayLog(*events)), record.camera,
                                       record.render_settings);
      }
    }
    if (!attached.ok()) {
      service_->sessions->Close(session->id(), user).IgnoreError();
      return attached;
    }
    for (const std::string& viewer : record.shared_with) session->access().Share(viewer, true);
    FillSessionInfo(*session, user, response);
    return absl::OkStatus();
  });
}

grpc::ServerUnaryReactor* VpmService::UpdateCase(grpc::CallbackServerContext* context,
                                                 const v3::UpdateCaseRequest* request,
                                                 v3::CaseInfo* response) {
  return Unary(context, *request, "UpdateCase", service_->request_pool,
               [=, this](const std::string& user) -> Status {
    if (request->has_title() && request->title().size() > kMaxTitleBytes) {
      return absl::InvalidArgumentError(StrCat("title: longer than ", kMaxTitleBytes, " bytes"));
    }
    ASSIGN_OR_RETURN(const cases::CaseRecord record, FindCase(request->case_id(), user, true));
    std::optional<std::string> title, notes;
    if (request->has_title()) title = request->title();
    if (request->has_notes()) notes = request->notes();
    RETURN_IF_ERROR(service_->cases->Update(record.id, title, notes));
    ASSIGN_OR_RETURN(const cases::CaseRecord updated, service_->cases->Get(record.id));
    FillCaseInfo(updated, user, response);
    return absl::OkStatus();
  });
}

grpc::ServerUnaryReactor* VpmService::DeleteCase(grpc::CallbackServerContext* context,
                                                 const v3::DeleteCaseRequest* request,
                                                 v3::DeleteCaseResponse*) {
  return Unary(context, *request, "DeleteCase", service_->request_pool,
               [=, this](const std::string& user) -> Status {
    ASSIGN_OR_RETURN(const cases::CaseRecord record, FindCase(request->case_id(), user, true));
    if (auto open = OpenSessionOf(record.id, user)) {
      service_->streams->FinishSession(
          open->id(), "", grpc::Status(grpc::PERMISSION_DENIED, "the case was deleted by its owner"));
      service_->sessions->Close(open->id(), user).IgnoreError();
    }
    RETURN_IF_ERROR(service_->cases->Delete(record.id));
    return ForgetKeptUpload(record.source);
  });
}

grpc::ServerUnaryReactor* VpmService::ShareCase(grpc::CallbackServerContext* context,
                                                const v3::ShareCaseRequest* request,
                                                v3::CaseInfo* response) {
  return Unary(context, *request, "ShareCase", service_->request_pool,
               [=, this](const std::string& user) -> Status {
    ASSIGN_OR_RETURN(const cases::CaseRecord record, FindCase(request->case_id(), user, true));
    if (!service_->auth->HasUser(request->user())) {
      return absl::InvalidArgumentError(StrCat("user: '", request->user(), "' is not a user of this server"));
    }
    RETURN_IF_ERROR(service_->cases->Share(record.id, request->user(), request->revoke()));
    if (auto open = OpenSessionOf(record.id, user)) {
      open->access().Share(request->user(), !request->revoke());
      if (request->revoke()) {
        service_->streams->FinishSession(
            open->id(), request->user(),
            grpc::Status(grpc::PERMISSION_DENIED, "the case is no longer shared with you"));
      }
    }
    ASSIGN_OR_RETURN(const cases::CaseRecord updated, service_->cases->Get(record.id));
    FillCaseInfo(updated, user, response);
    return absl::OkStatus();
  });
}

grpc::ServerUnaryReactor* VpmService::Undo(grpc::CallbackServerContext* context,
                                           const v3::UndoRequest* request,
                                           v3::UndoResponse* response) {
  return Unary(context, *request, "Undo", service_->render_pool,
               [=, this](const std::string& user) -> Status {
    ASSIGN_OR_RETURN(std::shared_ptr<Session> session,
                     service_->sessions->Get(request->session_id(), user, SessionRole::kOwner));
    ASSIGN_OR_RETURN(const Session::UndoOutcome outcome, session->Undo(request->redo()));
    response->set_changed(outcome.changed);
    response->set_max_displacement_mm(outcome.max_displacement_mm);
    response->set_events(outcome.events);
    response->set_undone(outcome.undone);
    return absl::OkStatus();
  });
}

grpc::ServerUnaryReactor* VpmService::ExportCase(grpc::CallbackServerContext* context,
                                                 const v3::ExportCaseRequest* request,
                                                 v3::CaseArchive* response) {
  return Unary(context, *request, "ExportCase", service_->request_pool,
               [=, this](const std::string& user, const CancelToken& cancel) -> Status {
    ASSIGN_OR_RETURN(const cases::CaseRecord record, FindCase(request->case_id(), user, false));
    if (record.source.starts_with("upload:")) {
      return absl::FailedPreconditionError(
          StrCat("case '", record.id, "': its volume is an upload, which an archive cannot "
                 "reference; another server could not open it"));
    }
    ASSIGN_OR_RETURN(const std::vector<cases::CaseEvent> events,
                     service_->cases->Events(record.id));
    // The volume's geometry turns the stored points into world LPS.
    ASSIGN_OR_RETURN(std::shared_ptr<VolumeEntry> volume,
                     service_->volumes->Load(record.source, user, {}, cancel));
    *response = ToCaseArchive(record, events, volume->volume.geometry());
    return absl::OkStatus();
  });
}

grpc::ServerUnaryReactor* VpmService::ImportCase(grpc::CallbackServerContext* context,
                                                 const v3::ImportCaseRequest* request,
                                                 v3::CaseInfo* response) {
  return Unary(context, *request, "ImportCase", service_->request_pool,
               [=, this](const std::string& user, const CancelToken& cancel) -> Status {
    ASSIGN_OR_RETURN(cases::CaseStore * store, Cases(service_));
    const v3::CaseArchive& archive = request->archive();
    if (archive.source().empty() || archive.source().starts_with("upload:")) {
      return absl::InvalidArgumentError("archive.source: a LoadVolume source is required");
    }
    if (archive.title().size() > kMaxTitleBytes) {
      return absl::InvalidArgumentError(StrCat("archive.title: longer than ", kMaxTitleBytes,
                                               " bytes"));
    }
    ASSIGN_OR_RETURN(std::shared_ptr<VolumeEntry> volume,
                     service_->volumes->Load(archive.source(), user, {}, cancel));
    const VolumeGeometry& geometry = volume->volume.geometry();
    RETURN_IF_ERROR(ToMeshParams(archive.mesh_params(), geometry).status());
    ASSIGN_OR_RETURN(const std::vector<cases::CaseEvent> events,
                     EventsFromArchive(archive, geometry));
    cases::CaseRecord record;
    record.id = StrCat("case-", RandomHex(16));
    record.owner = user;
    record.title = archive.title();
    record.notes = archive.notes();
    record.source = archive.source();
    record.mesh_params = archive.mesh_params().SerializeAsString();
    if (archive.has_camera()) record.camera = archive.camera().SerializeAsString();
    ASSIGN_OR_RETURN(record.render_settings,
                     ArchivedView(archive, volume->volume, service_->options.max_frame_side));
    RETURN_IF_ERROR(store->Create(record));
    // A failure part way leaves no half case behind.
    Status stored = absl::OkStatus();
    for (const cases::CaseEvent& e : events) {
      stored = store->Append(record.id, e.op, 0.0).status();
      if (stored.ok() && e.settled) stored = store->MarkSettled(record.id);
      if (!stored.ok()) break;
    }
    if (!stored.ok()) {
      store->Delete(record.id).IgnoreError();
      return stored;
    }
    ASSIGN_OR_RETURN(const cases::CaseRecord created, store->Get(record.id));
    FillCaseInfo(created, user, response);
    return absl::OkStatus();
  });
}

}  // namespace vpm::service
