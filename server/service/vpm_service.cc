#include "server/service/vpm_service.h"

#include "server/service/grpc_status.h"
#include "server/service/interact_reactor.h"
#include "server/service/proto_convert.h"
#include "server/service/upload_volume_reactor.h"
#include "server/service/watch_reactor.h"

namespace vpm::service {

grpc::ServerUnaryReactor* VpmService::Unary(grpc::CallbackServerContext* context,
                                            const char* method, WorkerPool* pool,
                                            std::function<Status()> fn) {
  grpc::ServerUnaryReactor* reactor = context->DefaultReactor();
  if (Status auth = service_->auth->Check(*context); !auth.ok()) {
    Done(reactor, method, auth);
  } else if (pool == nullptr) {
    Done(reactor, method, fn());
  } else if (!pool->Post([this, context, reactor, method, fn = std::move(fn)] {
               // Work nobody waits for any more is dropped before it starts:
               // a cancelled or expired call must not delay the calls behind it.
               if (Status gone = CallGone(*context); !gone.ok()) {
                 service_->metrics->DroppedJob(method, gone.code() == absl::StatusCode::kCancelled
                                                           ? "cancelled"
                                                           : "deadline");
                 Done(reactor, method, gone);
                 return;
               }
               Done(reactor, method, fn());
             })) {
    Done(reactor, method, absl::UnavailableError("the server is shutting down"));
  }
  return reactor;
}

Status VpmService::CallGone(grpc::CallbackServerContext& context) {
  if (context.IsCancelled()) {
    return absl::CancelledError("the call was cancelled before its turn on the server");
  }
  if (std::chrono::system_clock::now() > context.deadline()) {
    return absl::DeadlineExceededError("the call's deadline passed while it waited in the queue");
  }
  return absl::OkStatus();
}

void VpmService::Done(grpc::ServerUnaryReactor* reactor, const char* method,
                      const Status& status) {
  const grpc::Status g = ToGrpcStatus(status);
  service_->metrics->Request(method, StatusCodeName(g.error_code()));
  reactor->Finish(g);
}

void VpmService::FillSessionInfo(const Session& session, v2::SessionInfo* info) const {
  info->set_session_id(session.id());
  info->set_volume_id(session.volume().id);
  info->set_mesh_id(session.mesh().id);
  info->set_viewers(session.viewers());
  info->set_idle_s(session.idle_s());
}

grpc::ServerUnaryReactor* VpmService::LoadVolume(grpc::CallbackServerContext* context,
                                                 const v2::LoadVolumeRequest* request,
                                                 v2::VolumeInfo* response) {
  return Unary(context, "LoadVolume", service_->request_pool, [=, this]() -> Status {
    if (request->source().empty()) return absl::InvalidArgumentError("source: required");
    const std::string& progress_id = request->progress_id();
    LoadProgressRegistry* registry = service_->load_progress;
    if (progress_id.empty() || registry == nullptr) {
      ASSIGN_OR_RETURN(std::shared_ptr<VolumeEntry> entry,
                       service_->volumes->Load(request->source()));
      FillVolumeInfo(*entry, response);
      return absl::OkStatus();
    }
    RETURN_IF_ERROR(registry->Start(progress_id));
    Result<std::shared_ptr<VolumeEntry>> entry =
        service_->volumes->Load(request->source(), registry->Reporter(progress_id));
    registry->Finish(progress_id, entry.status());
    RETURN_IF_ERROR(entry.status());
    FillVolumeInfo(**entry, response);
    return absl::OkStatus();
  });
}

grpc::ServerUnaryReactor* VpmService::GetLoadProgress(grpc::CallbackServerContext* context,
                                                      const v2::GetLoadProgressRequest* request,
                                                      v2::LoadProgress* response) {
  return Unary(context, "GetLoadProgress", nullptr, [=, this]() -> Status {
    if (service_->load_progress == nullptr) return absl::UnimplementedError("no load progress");
    ASSIGN_OR_RETURN(const LoadProgressState state,
                     service_->load_progress->Get(request->progress_id()));
    response->set_fraction(state.fraction);
    response->set_stage(state.stage);
    response->set_done(state.done);
    response->set_error_code(static_cast<int32_t>(state.status.code()));
    response->set_error_message(std::string(state.status.message()));
    return absl::OkStatus();
  });
}

grpc::ServerReadReactor<v2::UploadVolumeRequest>* VpmService::UploadVolume(
    grpc::CallbackServerContext* context, v2::VolumeInfo* response) {
  return new UploadVolumeReactor(service_, context, response);
}

grpc::ServerUnaryReactor* VpmService::GetVolume(grpc::CallbackServerContext* context,
                                                const v2::GetVolumeRequest* request,
                                                v2::VolumeInfo* response) {
  return Unary(context, "GetVolume", nullptr, [=, this]() -> Status {
    ASSIGN_OR_RETURN(std::shared_ptr<VolumeEntry> entry,
                     service_->volumes->Get(request->volume_id()));
    FillVolumeInfo(*entry, response);
    return absl::OkStatus();
  });
}

grpc::ServerUnaryReactor* VpmService::ListVolumes(grpc::CallbackServerContext* context,
                                                  const v2::ListVolumesRequest*,
                                                  v2::ListVolumesResponse* response) {
  return Unary(context, "ListVolumes", nullptr, [=, this]() -> Status {
    for (const auto& entry : service_->volumes->List()) {
      FillVolumeInfo(*entry, response->add_volumes());
    }
    return absl::OkStatus();
  });
}

grpc::ServerUnaryReactor* VpmService::DeleteVolume(grpc::CallbackServerContext* context,
                                                   const v2::DeleteVolumeRequest* request,
                                                   v2::DeleteVolumeResponse*) {
  return Unary(context, "DeleteVolume", nullptr, [=, this]() -> Status {
    RETURN_IF_ERROR(service_->volumes->Delete(request->volume_id()));
    service_->meshes->ForgetVolume(request->volume_id());
    return absl::OkStatus();
  });
}

grpc::ServerUnaryReactor* VpmService::BuildMesh(grpc::CallbackServerContext* context,
                                                const v2::BuildMeshRequest* request,
                                                v2::MeshInfo* response) {
  return Unary(context, "BuildMesh", service_->request_pool, [=, this]() -> Status {
    ASSIGN_OR_RETURN(std::shared_ptr<VolumeEntry> volume,
                     service_->volumes->Get(request->volume_id()));
    ASSIGN_OR_RETURN(MeshParams params, ToMeshParams(request->params()));
    ASSIGN_OR_RETURN(std::shared_ptr<const MeshEntry> mesh,
                     service_->meshes->Build(volume, params));
    FillMeshInfo(*mesh, response);
    return absl::OkStatus();
  });
}

grpc::ServerUnaryReactor* VpmService::GetMesh(grpc::CallbackServerContext* context,
                                              const v2::GetMeshRequest* request,
                                              v2::GetMeshResponse* response) {
  return Unary(context, "GetMesh", nullptr, [=, this]() -> Status {
    ASSIGN_OR_RETURN(std::shared_ptr<const MeshEntry> mesh,
                     service_->meshes->Get(request->mesh_id()));
    FillMeshInfo(*mesh, response->mutable_info());
    if (request->include_geometry()) FillMeshGeometry(mesh->mesh, response);
    return absl::OkStatus();
  });
}

grpc::ServerUnaryReactor* VpmService::RefineMesh(grpc::CallbackServerContext* context,
                                                 const v2::RefineMeshRequest* request,
                                                 v2::MeshInfo* response) {
  return Unary(context, "RefineMesh", service_->request_pool, [=, this]() -> Status {
    if (!request->has_point_mm()) return absl::InvalidArgumentError("point_mm: required");
    ASSIGN_OR_RETURN(std::shared_ptr<const MeshEntry> mesh,
                     service_->meshes->Refine(request->mesh_id(), FromProto(request->point_mm())));
    FillMeshInfo(*mesh, response);
    return absl::OkStatus();
  });
}

grpc::ServerUnaryReactor* VpmService::DeleteMesh(grpc::CallbackServerContext* context,
                                                 const v2::DeleteMeshRequest* request,
                                                 v2::DeleteMeshResponse*) {
  return Unary(context, "DeleteMesh", service_->request_pool, [=, this]() -> Status {
    return service_->meshes->Delete(request->mesh_id());
  });
}

grpc::ServerUnaryReactor* VpmService::OpenSession(grpc::CallbackServerContext* context,
                                                  const v2::OpenSessionRequest* request,
                                                  v2::SessionInfo* response) {
  return Unary(context, "OpenSession", service_->request_pool, [=, this]() -> Status {
    std::shared_ptr<const MeshEntry> mesh;
    if (!request->mesh_id().empty()) {
      ASSIGN_OR_RETURN(mesh, service_->meshes->Get(request->mesh_id()));
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
                       service_->volumes->Get(request->volume_id()));
      ASSIGN_OR_RETURN(mesh, service_->meshes->Build(volume, MeshParams{}));
    }
    ASSIGN_OR_RETURN(std::shared_ptr<Session> session,
                     service_->sessions->Open(mesh->volume, mesh));
    FillSessionInfo(*session, response);
    return absl::OkStatus();
  });
}

grpc::ServerUnaryReactor* VpmService::CloseSession(grpc::CallbackServerContext* context,
                                                   const v2::CloseSessionRequest* request,
                                                   v2::CloseSessionResponse*) {
  return Unary(context, "CloseSession", nullptr,
               [=, this] { return service_->sessions->Close(request->session_id()); });
}

grpc::ServerUnaryReactor* VpmService::ListSessions(grpc::CallbackServerContext* context,
                                                   const v2::ListSessionsRequest*,
                                                   v2::ListSessionsResponse* response) {
  return Unary(context, "ListSessions", nullptr, [=, this]() -> Status {
    for (const auto& session : service_->sessions->List()) {
      FillSessionInfo(*session, response->add_sessions());
    }
    return absl::OkStatus();
  });
}

grpc::ServerBidiReactor<v2::InteractRequest, v2::Frame>* VpmService::Interact(
    grpc::CallbackServerContext* context) {
  return new InteractReactor(service_, context);
}

grpc::ServerWriteReactor<v2::Frame>* VpmService::Watch(grpc::CallbackServerContext* context,
                                                       const v2::WatchRequest* request) {
  return new WatchReactor(service_, context, *request);
}

grpc::ServerUnaryReactor* VpmService::Manipulate(grpc::CallbackServerContext* context,
                                                 const v2::ManipulateRequest* request,
                                                 v2::ManipulateResponse* response) {
  return Unary(context, "Manipulate", service_->render_pool, [=, this]() -> Status {
    ASSIGN_OR_RETURN(std::shared_ptr<Session> session,
                     service_->sessions->Get(request->session_id()));
    const v2::ClientEvent& event = request->event();
    if (event.event_case() == v2::ClientEvent::EVENT_NOT_SET) {
      return absl::InvalidArgumentError("event: required (camera, grab, drag, pull or release)");
    }
    if (event.has_settings()) {
      return absl::InvalidArgumentError(
          "event.settings: render settings belong to a stream (WatchRequest.settings)");
    }
    ASSIGN_OR_RETURN(AppliedEvent applied, session->Apply(event));
    response->set_applied_sequence(event.sequence());
    response->set_max_displacement_mm(session->max_displacement_mm());
    if (applied.grab_point_mm) *response->mutable_grab_point_mm() = ToProto(*applied.grab_point_mm);
    return absl::OkStatus();
  });
}

grpc::ServerUnaryReactor* VpmService::SetCamera(grpc::CallbackServerContext* context,
                                                const v2::SetCameraRequest* request,
                                                v2::SetCameraResponse*) {
  return Unary(context, "SetCamera", nullptr, [=, this]() -> Status {
    ASSIGN_OR_RETURN(std::shared_ptr<Session> session,
                     service_->sessions->Get(request->session_id()));
    return session->SetCamera(request->camera());
  });
}

grpc::ServerUnaryReactor* VpmService::Render(grpc::CallbackServerContext* context,
                                             const v2::RenderRequest* request,
                                             v2::Frame* response) {
  return Unary(context, "Render", service_->render_pool, [=, this]() -> Status {
    ASSIGN_OR_RETURN(std::shared_ptr<Session> session,
                     service_->sessions->Get(request->session_id()));
    ASSIGN_OR_RETURN(StreamSettings settings,
                     ToStreamSettings(request->settings(), session->volume().volume,
                                      service_->options.max_frame_side));
    Session::FrameRequest frame_request{&settings, std::nullopt, false, false};
    if (request->has_camera()) {
      ASSIGN_OR_RETURN(frame_request.camera,
                       ToCamera(request->camera(), session->volume().volume.geometry()));
    }
    ASSIGN_OR_RETURN(*response, session->Render(frame_request));
    response->set_frame_number(1);
    service_->metrics->FrameSent(response->timings());
    return absl::OkStatus();
  });
}

}  // namespace vpm::service
