// vpm.v1.Vpm on gRPC's callback API. Unary calls check the token, then run
// cheap lookups inline and anything heavy (reads, mesh builds, FEM, frames)
// on a worker pool, finishing the call from there; streaming calls are
// reactors in their own files. Every call is counted by method and code.
#pragma once

#include <grpcpp/grpcpp.h>

#include "server/service/service_context.h"
#include "vpm/v1/vpm.grpc.pb.h"

namespace vpm::service {

class VpmService final : public v1::Vpm::CallbackService {
 public:
  explicit VpmService(ServiceContext* service) : service_(service) {}

  grpc::ServerUnaryReactor* LoadVolume(grpc::CallbackServerContext*, const v1::LoadVolumeRequest*,
                                       v1::VolumeInfo*) override;
  grpc::ServerReadReactor<v1::UploadVolumeRequest>* UploadVolume(grpc::CallbackServerContext*,
                                                                 v1::VolumeInfo*) override;
  grpc::ServerUnaryReactor* GetVolume(grpc::CallbackServerContext*, const v1::GetVolumeRequest*,
                                      v1::VolumeInfo*) override;
  grpc::ServerUnaryReactor* ListVolumes(grpc::CallbackServerContext*,
                                        const v1::ListVolumesRequest*,
                                        v1::ListVolumesResponse*) override;
  grpc::ServerUnaryReactor* DeleteVolume(grpc::CallbackServerContext*,
                                         const v1::DeleteVolumeRequest*,
                                         v1::DeleteVolumeResponse*) override;
  grpc::ServerUnaryReactor* BuildMesh(grpc::CallbackServerContext*, const v1::BuildMeshRequest*,
                                      v1::MeshInfo*) override;
  grpc::ServerUnaryReactor* GetMesh(grpc::CallbackServerContext*, const v1::GetMeshRequest*,
                                    v1::GetMeshResponse*) override;
  grpc::ServerUnaryReactor* RefineMesh(grpc::CallbackServerContext*, const v1::RefineMeshRequest*,
                                       v1::MeshInfo*) override;
  grpc::ServerUnaryReactor* OpenSession(grpc::CallbackServerContext*,
                                        const v1::OpenSessionRequest*, v1::SessionInfo*) override;
  grpc::ServerUnaryReactor* CloseSession(grpc::CallbackServerContext*,
                                         const v1::CloseSessionRequest*,
                                         v1::CloseSessionResponse*) override;
  grpc::ServerUnaryReactor* ListSessions(grpc::CallbackServerContext*,
                                         const v1::ListSessionsRequest*,
                                         v1::ListSessionsResponse*) override;
  grpc::ServerBidiReactor<v1::InteractRequest, v1::Frame>* Interact(
      grpc::CallbackServerContext*) override;
  grpc::ServerWriteReactor<v1::Frame>* Watch(grpc::CallbackServerContext*,
                                             const v1::WatchRequest*) override;
  grpc::ServerUnaryReactor* Manipulate(grpc::CallbackServerContext*, const v1::ManipulateRequest*,
                                       v1::ManipulateResponse*) override;
  grpc::ServerUnaryReactor* SetCamera(grpc::CallbackServerContext*, const v1::SetCameraRequest*,
                                      v1::SetCameraResponse*) override;
  grpc::ServerUnaryReactor* Render(grpc::CallbackServerContext*, const v1::RenderRequest*,
                                   v1::Frame*) override;

 private:
  // Checks the token, then runs `fn` inline (pool == nullptr) or on `pool`,
  // and finishes the call with its status.
  grpc::ServerUnaryReactor* Unary(grpc::CallbackServerContext* context, const char* method,
                                  WorkerPool* pool, std::function<Status()> fn);
  void Done(grpc::ServerUnaryReactor* reactor, const char* method, const Status& status);
  void FillSessionInfo(const Session& session, v1::SessionInfo* info) const;

  ServiceContext* service_;
};

}  // namespace vpm::service
