#include "server/service/vpm_service.h"

#include "proto/render_tf_convert.h"
#include "server/common/clock.h"
#include "server/io/read_paraview_preset.h"
#include "server/io/read_slicer_volume_property.h"
#include "server/service/grpc_status.h"
#include "server/service/interact_reactor.h"
#include "server/service/proto_convert.h"
#include "server/service/request_limits.h"
#include "server/service/upload_volume_reactor.h"
#include "server/service/watch_reactor.h"

namespace vpm::service {
namespace {

// A transfer function's file text (ReadTransferFunction): ParaView's whole
// preset list is about 1 MiB.
constexpr size_t kMaxTransferFunctionTextBytes = size_t{1} << 20;

}  // namespace

grpc::ServerUnaryReactor* VpmService::Unary(grpc::CallbackServerContext* context,
                                            const google::protobuf::Message& request,
                                            const char* method, WorkerPool* pool,
                                            std::function<Status(const std::string& user)> fn) {
  // Refused inline, after authentication, before any handler or queue sees
  // an over-long string.
  return Unary(context, request, method, pool,
               [fn = std::move(fn)](const std::string& user, const CancelToken&) {
                 return fn(user);
               });
}

grpc::ServerUnaryReactor* VpmService::Unary(
    grpc::CallbackServerContext* context, const google::protobuf::Message& request,
    const char* method, WorkerPool* pool,
    std::function<Status(const std::string& user, const CancelToken& cancel)> fn) {
  // Refused inline, after authentication, before any handler or queue sees
  // an over-long string.
  if (Status limits = CheckRequestLimits(request); !limits.ok()) {
    return Unary(context, method, nullptr, [limits](const std::string&) { return limits; });
  }
  return Unary(context, method, pool, std::move(fn));
}

grpc::ServerUnaryReactor* VpmService::Unary(grpc::CallbackServerContext* context,
                                            const char* method, WorkerPool* pool,
                                            std::function<Status(const std::string& user)> fn) {
  return Unary(context, method, pool,
               [fn = std::move(fn)](const std::string& user, const CancelToken&) {
                 return fn(user);
               });
}

CancelToken VpmService::CallToken(grpc::CallbackServerContext* context) const {
  return CancelToken([context, service = service_]() -> Status {
    if (context->IsCancelled()) return absl::CancelledError("the call was cancelled");
    if (std::chrono::system_clock::now() > context->deadline()) {
      return absl::DeadlineExceededError("the call's deadline passed while it ran");
    }
    return service->WorkAllowed();
  });
}

grpc::ServerUnaryReactor* VpmService::Unary(
    grpc::CallbackServerContext* context, const char* method, WorkerPool* pool,
    std::function<Status(const std::string& user, const CancelToken& cancel)> fn) {
  grpc::ServerUnaryReactor* reactor = context->DefaultReactor();
  service_->metrics->UnaryInFlight(method, +1);  // -1 in Done
  Result<std::string> authenticated = service_->auth->Authenticate(*context);
  if (!authenticated.ok()) {
    Done(reactor, method, authenticated.status(), "");
    return reactor;
  }
  const std::string user = *std::move(authenticated);
  if (pool == nullptr) {
    Done(reactor, method, fn(user, CancelToken()), user);
    return reactor;
  }
  // Dropped unrun, answered with `why`.
  auto dropped = [this, reactor, method, user](const Status& why) {
    service_->metrics->DroppedJob(method, why.code() == absl::StatusCode::kCancelled ? "cancelled"
                                          : why.code() == absl::StatusCode::kDeadlineExceeded
                                              ? "deadline"
                                              : "shutdown");
    Done(reactor, method, why, user);
  };
  // Purged to make room (gone), or still queued at shutdown.
  auto drop = [context, dropped] {
    Status gone = CallGone(*context);
    dropped(gone.ok() ? absl::UnavailableError("the server shut down before this call's turn")
                      : gone);
  };
  const std::string lane = StrCat("unary:", FairShareKey(user));
  Status queued = pool->Submit(Job{
      .lane = lane,
      .run =
          [this, context, reactor, method, fn = std::move(fn), dropped, user] {
            // Work nobody waits for any more is dropped before it starts: a
            // cancelled or expired call, or one whose deadline would pass
            // before a typical job here finishes, must not delay the calls
            // behind it.
            if (Status gone = CallGone(*context, 0.5 * run_times_.MeanMs(method)); !gone.ok()) {
              return dropped(gone);
            }
            const auto start = std::chrono::steady_clock::now();
            Status status = fn(user, CallToken(context));
            run_times_.Add(method, MsSince(start));
            Done(reactor, method, status, user);
          },
      .gone = [context] { return !CallGone(*context).ok(); },
      .drop = drop,
  });
  if (absl::IsResourceExhausted(queued)) {
    // gRPC's retry pushback trailer, and the same hint in words.
    const int64_t retry_ms = pool->RetryAfterMs(lane);
    context->AddTrailingMetadata("grpc-retry-pushback-ms", std::to_string(retry_ms));
    service_->metrics->DroppedJob(method, "queue_full");
    Done(reactor, method,
         absl::ResourceExhaustedError(StrCat(queued.message(), "; retry after about ", retry_ms,
                                             " ms")),
         user);
  } else if (!queued.ok()) {
    Done(reactor, method, queued, user);
  }
  return reactor;
}

std::string VpmService::FairShareKey(const std::string& user) { return user; }

Status VpmService::CallGone(grpc::CallbackServerContext& context, double need_ms) {
  if (context.IsCancelled()) {
    return absl::CancelledError("the call was cancelled before its turn on the server");
  }
  const auto now = std::chrono::system_clock::now();
  if (now > context.deadline()) {
    return absl::DeadlineExceededError("the call's deadline passed while it waited in the queue");
  }
  if (now + std::chrono::microseconds(int64_t(need_ms * 1000)) > context.deadline()) {
    return absl::DeadlineExceededError(StrCat("the call's deadline would pass before it could "
                                              "finish (a job here takes about ",
                                              int64_t(2 * need_ms), " ms)"));
  }
  return absl::OkStatus();
}

void VpmService::Done(grpc::ServerUnaryReactor* reactor, const char* method,
                      const Status& status, const std::string& user) {
  const grpc::Status g = ToGrpcStatus(status);
  service_->metrics->Request(method, StatusCodeName(g.error_code()), user);
  service_->metrics->UnaryInFlight(method, -1);
  reactor->Finish(g);
}

void VpmService::FillSessionInfo(const Session& session, const std::string& user,
                                 v3::SessionInfo* info) const {
  info->set_session_id(session.id());
  info->set_volume_id(session.volume().id);
  info->set_mesh_id(session.mesh()->id);
  info->set_viewers(session.viewers());
  info->set_idle_s(session.idle_s());
  info->set_owner(session.access().owner());
  info->set_case_id(session.case_id());
  if (session.access().IsOwner(user)) {
    for (const std::string& viewer : session.access().viewers()) info->add_shared_with(viewer);
  }
}

Result<std::shared_ptr<const MeshEntry>> VpmService::FindMesh(std::string_view mesh_id,
                                                             const std::string& user) const {
  ASSIGN_OR_RETURN(std::shared_ptr<const MeshEntry> mesh, service_->meshes->Get(mesh_id));
  // A mesh on another user's upload answers as a missing one.
  if (!CheckVolumeAccess(*mesh->volume, user).ok()) return MeshNotFound();
  return mesh;
}

grpc::ServerUnaryReactor* VpmService::LoadVolume(grpc::CallbackServerContext* context,
                                                 const v3::LoadVolumeRequest* request,
                                                 v3::VolumeInfo* response) {
  return Unary(context, *request, "LoadVolume", service_->request_pool,
               [=, this](const std::string& user, const CancelToken& cancel) -> Status {
    RETURN_IF_ERROR(service_->AcceptingNewWork());
    if (request->source().empty()) return absl::InvalidArgumentError("source: required");
    const std::string& progress_id = request->progress_id();
    LoadProgressRegistry* registry = service_->load_progress;
    if (progress_id.empty() || registry == nullptr) {
      ASSIGN_OR_RETURN(std::shared_ptr<VolumeEntry> entry,
                       service_->volumes->Load(request->source(), user, {}, cancel));
      FillVolumeInfo(*entry, response);
      return absl::OkStatus();
    }
    RETURN_IF_ERROR(registry->Start(user, progress_id));
    Result<std::shared_ptr<VolumeEntry>> entry = service_->volumes->Load(
        request->source(), user, registry->Reporter(user, progress_id), cancel);
    registry->Finish(user, progress_id, entry.status());
    RETURN_IF_ERROR(entry.status());
    FillVolumeInfo(**entry, response);
    return absl::OkStatus();
  });
}

grpc::ServerUnaryReactor* VpmService::GetLoadProgress(grpc::CallbackServerContext* context,
                                                      const v3::GetLoadProgressRequest* request,
                                                      v3::LoadProgress* response) {
  return Unary(context, *request, "GetLoadProgress", nullptr,
               [=, this](const std::string& user) -> Status {
    if (service_->load_progress == nullptr) return absl::UnimplementedError("no load progress");
    ASSIGN_OR_RETURN(const LoadProgressState state,
                     service_->load_progress->Get(user, request->progress_id()));
    response->set_fraction(state.fraction);
    response->set_stage(state.stage);
    response->set_done(state.done);
    response->set_error_code(static_cast<int32_t>(state.status.code()));
    response->set_error_message(BoundedStatusMessage(state.status.message()));
    return absl::OkStatus();
  });
}

grpc::ServerReadReactor<v3::UploadVolumeRequest>* VpmService::UploadVolume(
    grpc::CallbackServerContext* context, v3::VolumeInfo* response) {
  return UploadVolumeReactor::Make(service_, context, response);
}

grpc::ServerUnaryReactor* VpmService::GetVolume(grpc::CallbackServerContext* context,
                                                const v3::GetVolumeRequest* request,
                                                v3::VolumeInfo* response) {
  // On a pool: an evicted volume is read again.
  return Unary(context, *request, "GetVolume", service_->request_pool,
               [=, this](const std::string& user) -> Status {
    ASSIGN_OR_RETURN(std::shared_ptr<VolumeEntry> entry,
                     service_->volumes->Get(request->volume_id(), user));
    FillVolumeInfo(*entry, response);
    return absl::OkStatus();
  });
}

grpc::ServerUnaryReactor* VpmService::ListVolumes(grpc::CallbackServerContext* context,
                                                  const v3::ListVolumesRequest*,
                                                  v3::ListVolumesResponse* response) {
  return Unary(context, "ListVolumes", nullptr, [=, this](const std::string& user) -> Status {
    for (const auto& entry : service_->volumes->List(user)) {
      FillVolumeInfo(*entry, response->add_volumes());
    }
    return absl::OkStatus();
  });
}

grpc::ServerUnaryReactor* VpmService::DeleteVolume(grpc::CallbackServerContext* context,
                                                   const v3::DeleteVolumeRequest* request,
                                                   v3::DeleteVolumeResponse*) {
  return Unary(context, *request, "DeleteVolume", service_->request_pool,
               [=, this](const std::string& user) -> Status {
    RETURN_IF_ERROR(service_->volumes->Delete(request->volume_id(), user));
    service_->meshes->ForgetVolume(request->volume_id());
    return absl::OkStatus();
  });
}

grpc::ServerUnaryReactor* VpmService::BuildMesh(grpc::CallbackServerContext* context,
                                                const v3::BuildMeshRequest* request,
                                                v3::MeshInfo* response) {
  return Unary(context, *request, "BuildMesh", service_->request_pool,
               [=, this](const std::string& user, const CancelToken& cancel) -> Status {
    RETURN_IF_ERROR(service_->AcceptingNewWork());
    ASSIGN_OR_RETURN(std::shared_ptr<VolumeEntry> volume,
                     service_->volumes->Get(request->volume_id(), user));
    ASSIGN_OR_RETURN(MeshParams params, ToMeshParams(request->params(), volume->volume.geometry()));
    ASSIGN_OR_RETURN(std::shared_ptr<const MeshEntry> mesh,
                     service_->meshes->Build(volume, params, cancel));
    FillMeshInfo(*mesh, response);
    return absl::OkStatus();
  });
}

grpc::ServerUnaryReactor* VpmService::GetMesh(grpc::CallbackServerContext* context,
                                              const v3::GetMeshRequest* request,
                                              v3::GetMeshResponse* response) {
  return Unary(context, *request, "GetMesh", service_->request_pool,
               [=, this](const std::string& user) -> Status {
    ASSIGN_OR_RETURN(std::shared_ptr<const MeshEntry> mesh, FindMesh(request->mesh_id(), user));
    FillMeshInfo(*mesh, response->mutable_info());
    if (request->include_geometry()) {
      FillMeshGeometry(mesh->mesh, mesh->volume->volume.geometry(), response);
    }
    return absl::OkStatus();
  });
}

grpc::ServerUnaryReactor* VpmService::RefineMesh(grpc::CallbackServerContext* context,
                                                 const v3::RefineMeshRequest* request,
                                                 v3::MeshInfo* response) {
  return Unary(context, *request, "RefineMesh", service_->request_pool,
               [=, this](const std::string& user, const CancelToken& cancel) -> Status {
    RETURN_IF_ERROR(service_->AcceptingNewWork());
    if (!request->has_point_mm()) return absl::InvalidArgumentError("point_mm: required");
    ASSIGN_OR_RETURN(std::shared_ptr<const MeshEntry> held, FindMesh(request->mesh_id(), user));
    const VolumeGeometry mesh_geometry = held->volume->volume.geometry();
    ASSIGN_OR_RETURN(std::shared_ptr<const MeshEntry> mesh,
                     service_->meshes->Refine(request->mesh_id(),
                                              PointFromApi(request->point_mm(),
                                                           mesh_geometry),
                                              cancel));
    FillMeshInfo(*mesh, response);
    return absl::OkStatus();
  });
}

grpc::ServerUnaryReactor* VpmService::DeleteMesh(grpc::CallbackServerContext* context,
                                                 const v3::DeleteMeshRequest* request,
                                                 v3::DeleteMeshResponse*) {
  return Unary(context, *request, "DeleteMesh", service_->request_pool,
               [=, this](const std::string& user) -> Status {
    RETURN_IF_ERROR(FindMesh(request->mesh_id(), user).status());
    return service_->meshes->Delete(request->mesh_id());
  });
}

grpc::ServerUnaryReactor* VpmService::OpenSession(grpc::CallbackServerContext* context,
                                                  const v3::OpenSessionRequest* request,
                                                  v3::SessionInfo* response) {
  return Unary(context, *request, "OpenSession", service_->request_pool,
               [=, this](const std::string& user, const CancelToken& cancel) -> Status {
    RETURN_IF_ERROR(service_->AcceptingNewWork());
    std::shared_ptr<const MeshEntry> mesh;
    if (!request->mesh_id().empty()) {
      ASSIGN_OR_RETURN(mesh, FindMesh(request->mesh_id(), user));
      if (!request->volume_id().empty() && mesh->volume->id != request->volume_id()) {
        return absl::InvalidArgumentError(StrCat("mesh_id: '", request->mesh_id(),
                                                 "' was built on volume '", mesh->volume->id,
                                                 "', not '", request->volume_id(), "'"));
      }
    } else {
      if (request->volume_id().empty()) {
        return absl::InvalidArgumentError("volume_id: required (or a mesh_id)");
      }
      ASSIGN_OR_RETURN(std::shared_ptr<VolumeEntry> volume,
                       service_->volumes->Get(request->volume_id(), user));
      ASSIGN_OR_RETURN(mesh, service_->meshes->Build(volume, MeshParams{}, cancel));
    }
    RETURN_IF_ERROR(cancel.Check());
    ASSIGN_OR_RETURN(VolumeHold hold, service_->volumes->HoldForSession(mesh->volume, user));
    ASSIGN_OR_RETURN(std::shared_ptr<Session> session,
                     service_->sessions->Open(user, std::move(hold), mesh));
    // A client gone while the scene was built (a closed tab, a sign-out)
    // would never close it: it is closed now, not after --idle-session-s.
    Status started = cancel.Check();
    if (started.ok()) started = StartCase(*session, user);
    if (!started.ok()) {
      service_->sessions->Close(session->id(), user).IgnoreError();
      return started;
    }
    FillSessionInfo(*session, user, response);
    return absl::OkStatus();
  });
}

grpc::ServerUnaryReactor* VpmService::CloseSession(grpc::CallbackServerContext* context,
                                                   const v3::CloseSessionRequest* request,
                                                   v3::CloseSessionResponse*) {
  return Unary(context, *request, "CloseSession", service_->request_pool, [=, this](const std::string& user) {
    // Only the owner gets this far; its streams, and its viewers', end at
    // once with PERMISSION_DENIED (before Close's own notice, which would
    // say FAILED_PRECONDITION: the first finish wins).
    RETURN_IF_ERROR(
        service_->sessions->Get(request->session_id(), user, SessionRole::kOwner).status());
    service_->streams->FinishSession(
        request->session_id(), "",
        grpc::Status(grpc::PERMISSION_DENIED, "the session was closed by its owner"));
    return service_->sessions->Close(request->session_id(), user);
  });
}

grpc::ServerUnaryReactor* VpmService::ListSessions(grpc::CallbackServerContext* context,
                                                   const v3::ListSessionsRequest*,
                                                   v3::ListSessionsResponse* response) {
  return Unary(context, "ListSessions", nullptr, [=, this](const std::string& user) -> Status {
    for (const auto& session : service_->sessions->List(user)) {
      FillSessionInfo(*session, user, response->add_sessions());
    }
    return absl::OkStatus();
  });
}

grpc::ServerUnaryReactor* VpmService::GetSession(grpc::CallbackServerContext* context,
                                                 const v3::GetSessionRequest* request,
                                                 v3::SessionInfo* response) {
  return Unary(context, *request, "GetSession", nullptr, [=, this](const std::string& user) -> Status {
    ASSIGN_OR_RETURN(std::shared_ptr<Session> session,
                     service_->sessions->Get(request->session_id(), user, SessionRole::kViewer));
    FillSessionInfo(*session, user, response);
    return absl::OkStatus();
  });
}

grpc::ServerUnaryReactor* VpmService::ShareSession(grpc::CallbackServerContext* context,
                                                   const v3::ShareSessionRequest* request,
                                                   v3::SessionInfo* response) {
  return Unary(context, *request, "ShareSession", nullptr, [=, this](const std::string& user) -> Status {
    ASSIGN_OR_RETURN(std::shared_ptr<Session> session,
                     service_->sessions->Get(request->session_id(), user, SessionRole::kOwner));
    if (!service_->auth->HasUser(request->user())) {
      return absl::InvalidArgumentError(
          StrCat("user: '", request->user(), "' is not a user of this server"));
    }
    if (request->user() == user) {
      return absl::InvalidArgumentError("user: a session is always its owner's");
    }
    session->access().Share(request->user(), !request->revoke());
    if (request->revoke()) {
      // The viewer's open streams end now, not at their next frame (which
      // they would not get either: FrameStream checks access per frame).
      service_->streams->FinishSession(
          session->id(), request->user(),
          grpc::Status(grpc::PERMISSION_DENIED, "the session's owner stopped sharing it with you"));
    }
    FillSessionInfo(*session, user, response);
    return absl::OkStatus();
  });
}

grpc::ServerBidiReactor<v3::InteractRequest, v3::Frame>* VpmService::Interact(
    grpc::CallbackServerContext* context) {
  return InteractReactor::Make<InteractReactor>(service_, context);
}

grpc::ServerWriteReactor<v3::Frame>* VpmService::Watch(grpc::CallbackServerContext* context,
                                                       const v3::WatchRequest* request) {
  return WatchReactor::Make<WatchReactor>(service_, context, *request);
}

grpc::ServerUnaryReactor* VpmService::Manipulate(grpc::CallbackServerContext* context,
                                                 const v3::ManipulateRequest* request,
                                                 v3::ManipulateResponse* response) {
  return Unary(context, *request, "Manipulate", service_->render_pool,
               [=, this](const std::string& user) -> Status {
    ASSIGN_OR_RETURN(std::shared_ptr<Session> session,
                     service_->sessions->Get(request->session_id(), user, SessionRole::kOwner));
    const v3::ClientEvent& event = request->event();
    if (event.event_case() == v3::ClientEvent::EVENT_NOT_SET) {
      return absl::InvalidArgumentError("event: required (camera, grab, drag, pull, release, pin or reset)");
    }
    if (event.has_settings()) {
      return absl::InvalidArgumentError(
          "event.settings: render settings belong to a stream (WatchRequest.settings)");
    }
    ASSIGN_OR_RETURN(AppliedEvent applied, session->Apply(event));
    response->set_applied_sequence(event.sequence());
    response->set_max_displacement_mm(session->max_displacement_mm());
    response->set_inverted_tets(applied.step.inverted_tets);
    response->set_lag_mm(applied.step.lag_mm);
    if (applied.grab_point_mm) {
      *response->mutable_grab_point_mm() =
          PointToApi(*applied.grab_point_mm, session->volume().volume.geometry());
    }
    if (applied.grab) {
      response->set_handles(static_cast<int32_t>(applied.grab->handles.size()));
      response->set_message(applied.grab->message);
    }
    return absl::OkStatus();
  });
}

grpc::ServerUnaryReactor* VpmService::SetCamera(grpc::CallbackServerContext* context,
                                                const v3::SetCameraRequest* request,
                                                v3::SetCameraResponse*) {
  return Unary(context, *request, "SetCamera", service_->render_pool,
               [=, this](const std::string& user) -> Status {
    ASSIGN_OR_RETURN(std::shared_ptr<Session> session,
                     service_->sessions->Get(request->session_id(), user, SessionRole::kOwner));
    return session->SetCamera(request->camera());
  });
}

grpc::ServerUnaryReactor* VpmService::Render(grpc::CallbackServerContext* context,
                                             const v3::RenderRequest* request,
                                             v3::Frame* response) {
  return Unary(context, *request, "Render", service_->render_pool,
               [=, this](const std::string& user, const CancelToken& cancel) -> Status {
    ASSIGN_OR_RETURN(std::shared_ptr<Session> session,
                     service_->sessions->Get(request->session_id(), user, SessionRole::kViewer));
    ASSIGN_OR_RETURN(StreamSettings settings,
                     ToStreamSettings(request->settings(), session->volume().volume,
                                      service_->options.max_frame_side));
    Session::FrameRequest frame_request{&settings, std::nullopt, false, false, cancel};
    if (request->has_camera()) {
      ASSIGN_OR_RETURN(frame_request.camera,
                       ToCamera(request->camera(), session->volume().volume.geometry()));
    }
    RETURN_IF_ERROR(cancel.Check());
    ASSIGN_OR_RETURN(*response, session->Render(frame_request));
    response->set_frame_number(1);
    service_->metrics->FrameSent(response->timings());
    return absl::OkStatus();
  });
}

grpc::ServerUnaryReactor* VpmService::RenderSlice(grpc::CallbackServerContext* context,
                                                  const v3::RenderSliceRequest* request,
                                                  v3::Frame* response) {
  return Unary(context, *request, "RenderSlice", service_->render_pool,
               [=, this](const std::string& user) -> Status {
    ASSIGN_OR_RETURN(std::shared_ptr<Session> session,
                     service_->sessions->Get(request->session_id(), user, SessionRole::kViewer));
    ASSIGN_OR_RETURN(SliceRequest slice,
                     ToSliceRequest(request->slice(), session->volume().volume,
                                    service_->options.max_frame_side, "slice"));
    ASSIGN_OR_RETURN(const FrameEncoding encoding,
                     ToFrameEncoding(request->encoding(), request->jpeg_quality(), ""));
    ASSIGN_OR_RETURN(*response,
                     session->RenderSlice(slice, encoding.png, encoding.jpeg_quality));
    response->set_frame_number(1);
    service_->metrics->FrameSent(response->timings());
    return absl::OkStatus();
  });
}

grpc::ServerUnaryReactor* VpmService::ReadTransferFunction(
    grpc::CallbackServerContext* context, const v3::ReadTransferFunctionRequest* request,
    v3::RenderTransferFunction* response) {
  return Unary(context, *request, "ReadTransferFunction", service_->request_pool,
               [=](const std::string&) -> Status {
    const std::string& name = request->file_name();
    const std::string what = StrCat("file '", name.substr(0, 128), "'");
    if (request->text().size() > kMaxTransferFunctionTextBytes) {
      return absl::InvalidArgumentError(StrCat(what, ": ", request->text().size(),
                                               " bytes; at most ",
                                               kMaxTransferFunctionTextBytes));
    }
    RenderTransferFunction tf;
    if (name.ends_with(".json") && !name.ends_with(".vp.json")) {
      ASSIGN_OR_RETURN(tf, ParseParaviewPreset(request->text(), request->preset(), what));
    } else if (name.ends_with(".vp")) {
      if (!request->preset().empty()) {
        return absl::InvalidArgumentError(
            StrCat(what, ": preset picks a ParaView preset; a Slicer .vp holds one property"));
      }
      const std::string stem = name.substr(0, name.size() - 3);
      ASSIGN_OR_RETURN(tf, ParseSlicerVolumeProperty(request->text(),
                                                     stem.substr(stem.find_last_of("/\\") + 1),
                                                     what));
    } else {
      return absl::InvalidArgumentError(
          StrCat(what, ": name a ParaView preset file (.json) or a 3D Slicer volume property (.vp)"));
    }
    *response = ToProto(tf);
    return absl::OkStatus();
  });
}

}  // namespace vpm::service
