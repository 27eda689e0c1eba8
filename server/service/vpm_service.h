// vpm.v2.Vpm on gRPC's callback API. Unary calls check the token, then run
// cheap lookups inline and anything heavy (reads, mesh builds, FEM, frames)
// on a worker pool, finishing the call from there; streaming calls are
// reactors in their own files. Every call is counted by method and code.
#pragma once

#include <grpcpp/grpcpp.h>

#include "server/service/service_context.h"
#include "vpm/v2/vpm.grpc.pb.h"

namespace vpm::service {

class VpmService final : public v2::Vpm::CallbackService {
 public:
  explicit VpmService(ServiceContext* service) : service_(service) {}

  grpc::ServerUnaryReactor* LoadVolume(grpc::CallbackServerContext*, const v2::LoadVolumeRequest*,
                                       v2::VolumeInfo*) override;
  grpc::ServerReadReactor<v2::UploadVolumeRequest>* UploadVolume(grpc::CallbackServerContext*,
                                                                 v2::VolumeInfo*) override;
  grpc::ServerUnaryReactor* GetLoadProgress(grpc::CallbackServerContext*,
                                            const v2::GetLoadProgressRequest*,
                                            v2::LoadProgress*) override;
  grpc::ServerUnaryReactor* GetVolume(grpc::CallbackServerContext*, const v2::GetVolumeRequest*,
                                      v2::VolumeInfo*) override;
  grpc::ServerUnaryReactor* ListVolumes(grpc::CallbackServerContext*,
                                        const v2::ListVolumesRequest*,
                                        v2::ListVolumesResponse*) override;
  grpc::ServerUnaryReactor* DeleteVolume(grpc::CallbackServerContext*,
                                         const v2::DeleteVolumeRequest*,
                                         v2::DeleteVolumeResponse*) override;
  grpc::ServerUnaryReactor* BuildMesh(grpc::CallbackServerContext*, const v2::BuildMeshRequest*,
                                      v2::MeshInfo*) override;
  grpc::ServerUnaryReactor* GetMesh(grpc::CallbackServerContext*, const v2::GetMeshRequest*,
                                    v2::GetMeshResponse*) override;
  grpc::ServerUnaryReactor* RefineMesh(grpc::CallbackServerContext*, const v2::RefineMeshRequest*,
                                       v2::MeshInfo*) override;
  grpc::ServerUnaryReactor* DeleteMesh(grpc::CallbackServerContext*, const v2::DeleteMeshRequest*,
                                       v2::DeleteMeshResponse*) override;
  grpc::ServerUnaryReactor* OpenSession(grpc::CallbackServerContext*,
                                        const v2::OpenSessionRequest*, v2::SessionInfo*) override;
  grpc::ServerUnaryReactor* CloseSession(grpc::CallbackServerContext*,
                                         const v2::CloseSessionRequest*,
                                         v2::CloseSessionResponse*) override;
  grpc::ServerUnaryReactor* ListSessions(grpc::CallbackServerContext*,
                                         const v2::ListSessionsRequest*,
                                         v2::ListSessionsResponse*) override;
  grpc::ServerBidiReactor<v2::InteractRequest, v2::Frame>* Interact(
      grpc::CallbackServerContext*) override;
  grpc::ServerWriteReactor<v2::Frame>* Watch(grpc::CallbackServerContext*,
                                             const v2::WatchRequest*) override;
  grpc::ServerUnaryReactor* Manipulate(grpc::CallbackServerContext*, const v2::ManipulateRequest*,
                                       v2::ManipulateResponse*) override;
  grpc::ServerUnaryReactor* SetCamera(grpc::CallbackServerContext*, const v2::SetCameraRequest*,
                                      v2::SetCameraResponse*) override;
  grpc::ServerUnaryReactor* Render(grpc::CallbackServerContext*, const v2::RenderRequest*,
                                   v2::Frame*) override;

 private:
  // Checks the token, then runs `fn` inline (pool == nullptr) or on `pool`,
  // and finishes the call with its status.
  grpc::ServerUnaryReactor* Unary(grpc::CallbackServerContext* context, const char* method,
                                  WorkerPool* pool, std::function<Status()> fn);
  void Done(grpc::ServerUnaryReactor* reactor, const char* method, const Status& status);
  // Cancelled or DeadlineExceeded when the client no longer waits for the call.
  static Status CallGone(grpc::CallbackServerContext& context);
  void FillSessionInfo(const Session& session, v2::SessionInfo* info) const;

  ServiceContext* service_;
};

}  // namespace vpm::service
