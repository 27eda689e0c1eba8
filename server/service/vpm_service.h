// vpm.v3.Vpm on gRPC's callback API. Unary calls authenticate the caller
// (token_auth.h: every call knows its user, for ownership checks and
// per-user metrics), then run
// cheap lookups inline and anything heavy (reads, mesh builds, FEM, frames)
// on a worker pool, finishing the call from there; streaming calls are
// reactors in their own files. Every call is counted by method and code.
#pragma once

#include <map>
#include <mutex>
#include <set>
#include <string>

#include <grpcpp/grpcpp.h>

#include "server/common/cancel_token.h"
#include "server/service/service_context.h"
#include "vpm/v3/vpm.grpc.pb.h"

namespace vpm::service {

class VpmService final : public v3::Vpm::CallbackService {
 public:
  explicit VpmService(ServiceContext* service) : service_(service) {}

  grpc::ServerUnaryReactor* LoadVolume(grpc::CallbackServerContext*, const v3::LoadVolumeRequest*,
                                       v3::VolumeInfo*) override;
  grpc::ServerReadReactor<v3::UploadVolumeRequest>* UploadVolume(grpc::CallbackServerContext*,
                                                                 v3::VolumeInfo*) override;
  grpc::ServerUnaryReactor* GetLoadProgress(grpc::CallbackServerContext*,
                                            const v3::GetLoadProgressRequest*,
                                            v3::LoadProgress*) override;
  grpc::ServerUnaryReactor* GetVolume(grpc::CallbackServerContext*, const v3::GetVolumeRequest*,
                                      v3::VolumeInfo*) override;
  grpc::ServerUnaryReactor* ListVolumes(grpc::CallbackServerContext*,
                                        const v3::ListVolumesRequest*,
                                        v3::ListVolumesResponse*) override;
  grpc::ServerUnaryReactor* DeleteVolume(grpc::CallbackServerContext*,
                                         const v3::DeleteVolumeRequest*,
                                         v3::DeleteVolumeResponse*) override;
  grpc::ServerUnaryReactor* BuildMesh(grpc::CallbackServerContext*, const v3::BuildMeshRequest*,
                                      v3::MeshInfo*) override;
  grpc::ServerUnaryReactor* GetMesh(grpc::CallbackServerContext*, const v3::GetMeshRequest*,
                                    v3::GetMeshResponse*) override;
  grpc::ServerUnaryReactor* RefineMesh(grpc::CallbackServerContext*, const v3::RefineMeshRequest*,
                                       v3::MeshInfo*) override;
  grpc::ServerUnaryReactor* DeleteMesh(grpc::CallbackServerContext*, const v3::DeleteMeshRequest*,
                                       v3::DeleteMeshResponse*) override;
  grpc::ServerUnaryReactor* OpenSession(grpc::CallbackServerContext*,
                                        const v3::OpenSessionRequest*, v3::SessionInfo*) override;
  grpc::ServerUnaryReactor* CloseSession(grpc::CallbackServerContext*,
                                         const v3::CloseSessionRequest*,
                                         v3::CloseSessionResponse*) override;
  grpc::ServerUnaryReactor* ListSessions(grpc::CallbackServerContext*,
                                         const v3::ListSessionsRequest*,
                                         v3::ListSessionsResponse*) override;
  grpc::ServerUnaryReactor* GetSession(grpc::CallbackServerContext*, const v3::GetSessionRequest*,
                                       v3::SessionInfo*) override;
  grpc::ServerUnaryReactor* ShareSession(grpc::CallbackServerContext*,
                                         const v3::ShareSessionRequest*,
                                         v3::SessionInfo*) override;
  grpc::ServerBidiReactor<v3::InteractRequest, v3::Frame>* Interact(
      grpc::CallbackServerContext*) override;
  grpc::ServerWriteReactor<v3::Frame>* Watch(grpc::CallbackServerContext*,
                                             const v3::WatchRequest*) override;
  grpc::ServerUnaryReactor* Manipulate(grpc::CallbackServerContext*, const v3::ManipulateRequest*,
                                       v3::ManipulateResponse*) override;
  grpc::ServerUnaryReactor* SetCamera(grpc::CallbackServerContext*, const v3::SetCameraRequest*,
                                      v3::SetCameraResponse*) override;
  grpc::ServerUnaryReactor* Render(grpc::CallbackServerContext*, const v3::RenderRequest*,
                                   v3::Frame*) override;
  grpc::ServerUnaryReactor* RenderSlice(grpc::CallbackServerContext*,
                                        const v3::RenderSliceRequest*, v3::Frame*) override;
  grpc::ServerUnaryReactor* ReadTransferFunction(grpc::CallbackServerContext*,
                                                 const v3::ReadTransferFunctionRequest*,
                                                 v3::RenderTransferFunction*) override;
  // pacs_handlers.cc
  grpc::ServerUnaryReactor* ListPacsEndpoints(grpc::CallbackServerContext*,
                                              const v3::ListPacsEndpointsRequest*,
                                              v3::ListPacsEndpointsResponse*) override;
  grpc::ServerWriteReactor<v3::ExportDicomPart>* ExportDicom(
      grpc::CallbackServerContext*, const v3::ExportDicomRequest*) override;
  grpc::ServerUnaryReactor* SearchStudies(grpc::CallbackServerContext*,
                                          const v3::SearchStudiesRequest*,
                                          v3::SearchStudiesResponse*) override;
  grpc::ServerUnaryReactor* ListSeries(grpc::CallbackServerContext*, const v3::ListSeriesRequest*,
                                       v3::ListSeriesResponse*) override;
  grpc::ServerUnaryReactor* GetSeriesThumbnail(grpc::CallbackServerContext*,
                                               const v3::GetSeriesThumbnailRequest*,
                                               v3::SeriesThumbnail*) override;
  // data_root_handlers.cc
  grpc::ServerUnaryReactor* ListDataRoot(grpc::CallbackServerContext*,
                                         const v3::ListDataRootRequest*,
                                         v3::ListDataRootResponse*) override;
  // case_handlers.cc
  grpc::ServerUnaryReactor* ListCases(grpc::CallbackServerContext*, const v3::ListCasesRequest*,
                                      v3::ListCasesResponse*) override;
  grpc::ServerUnaryReactor* GetCase(grpc::CallbackServerContext*, const v3::GetCaseRequest*,
                                    v3::CaseInfo*) override;
  grpc::ServerUnaryReactor* OpenCase(grpc::CallbackServerContext*, const v3::OpenCaseRequest*,
                                     v3::SessionInfo*) override;
  grpc::ServerUnaryReactor* UpdateCase(grpc::CallbackServerContext*,
                                       const v3::UpdateCaseRequest*, v3::CaseInfo*) override;
  grpc::ServerUnaryReactor* DeleteCase(grpc::CallbackServerContext*,
                                       const v3::DeleteCaseRequest*,
                                       v3::DeleteCaseResponse*) override;
  grpc::ServerUnaryReactor* ShareCase(grpc::CallbackServerContext*, const v3::ShareCaseRequest*,
                                      v3::CaseInfo*) override;
  grpc::ServerUnaryReactor* Undo(grpc::CallbackServerContext*, const v3::UndoRequest*,
                                 v3::UndoResponse*) override;
  grpc::ServerUnaryReactor* ExportCase(grpc::CallbackServerContext*,
                                       const v3::ExportCaseRequest*, v3::CaseArchive*) override;
  grpc::ServerUnaryReactor* ImportCase(grpc::CallbackServerContext*,
                                       const v3::ImportCaseRequest*, v3::CaseInfo*) override;

 private:
  // Authenticates the caller, then runs `fn` with the caller's user name
  // inline (pool == nullptr) or on `pool`, and finishes the call with its
  // status. The second form hands long work the call's CancelToken
  // (CallToken) to pass down.
  grpc::ServerUnaryReactor* Unary(grpc::CallbackServerContext* context, const char* method,
                                  WorkerPool* pool,
                                  std::function<Status(const std::string& user)> fn);
  grpc::ServerUnaryReactor* Unary(
      grpc::CallbackServerContext* context, const char* method, WorkerPool* pool,
      std::function<Status(const std::string& user, const CancelToken& cancel)> fn);
  // The same two, for a request with strings: their lengths are checked
  // first (request_limits.h), and an over-long one is answered inline.
  grpc::ServerUnaryReactor* Unary(grpc::CallbackServerContext* context,
                                  const google::protobuf::Message& request, const char* method,
                                  WorkerPool* pool,
                                  std::function<Status(const std::string& user)> fn);
  grpc::ServerUnaryReactor* Unary(
      grpc::CallbackServerContext* context, const google::protobuf::Message& request,
      const char* method, WorkerPool* pool,
      std::function<Status(const std::string& user, const CancelToken& cancel)> fn);
  // Cancelled once the client cancels, DeadlineExceeded once the call's
  // deadline passes, Unavailable once the shutdown grace period is over;
  // valid while the call is (until it is finished).
  CancelToken CallToken(grpc::CallbackServerContext* context) const;
  void Done(grpc::ServerUnaryReactor* reactor, const char* method, const Status& status,
            const std::string& user);
  // How long each method's work takes (moving average, ms), so that a call
  // whose deadline leaves less than half of that is not started.
  class RunTimes {
   public:
    void Add(const char* method, double ms) {
      std::lock_guard lock(mutex_);
      double& mean = mean_ms_[method];
      mean = mean == 0.0 ? ms : 0.9 * mean + 0.1 * ms;
    }
    double MeanMs(const char* method) const {
      std::lock_guard lock(mutex_);
      auto it = mean_ms_.find(method);
      return it == mean_ms_.end() ? 0.0 : it->second;
    }

   private:
    mutable std::mutex mutex_;
    std::map<std::string, double, std::less<>> mean_ms_;
  };
  RunTimes run_times_;

  // Cancelled or DeadlineExceeded when the client no longer waits for the
  // call: cancelled, past its deadline, or with less than `need_ms` left.
  static Status CallGone(grpc::CallbackServerContext& context, double need_ms = 0.0);
  // Whose fair share a unary call counts against: the caller's user (behind
  // a gateway or a balancer every user shares one peer address, so a share
  // per address would be one share for all).
  static std::string FairShareKey(const std::string& user);
  // shared_with only for the owner.
  void FillSessionInfo(const Session& session, const std::string& user,
                       v3::SessionInfo* info) const;
  // A new case for a session just opened (with --state-dir), attached to
  // it (case_handlers.cc).
  Status StartCase(Session& session, const std::string& user);
  // The case `id` if `user` owns it (owner_only) or may read it; NotFound
  // otherwise, the same answer as for a missing case.
  Result<cases::CaseRecord> FindCase(const std::string& id, const std::string& user,
                                     bool owner_only) const;
  // The volume of a case: Load of its source, or its kept upload
  // (BlobStore) read again as the caller's.
  Result<std::shared_ptr<VolumeEntry>> LoadCaseVolume(const cases::CaseRecord& record,
                                                      const std::string& user,
                                                      const CancelToken& cancel);
  // A deleted case's kept upload, once no case keeps it.
  Status ForgetKeptUpload(const std::string& source);
  // The session open on case `id` for its owner, if any.
  std::shared_ptr<Session> OpenSessionOf(const std::string& id, const std::string& owner) const;
  void FillCaseInfo(const cases::CaseRecord& record, const std::string& user,
                    v3::CaseInfo* info) const;
  // NotFound (MeshNotFound) when missing or on another user's upload.
  Result<std::shared_ptr<const MeshEntry>> FindMesh(std::string_view mesh_id,
                                                   const std::string& user) const;

  ServiceContext* service_;
  // Cases being opened (OpenCase): a second open of the same case waits
  // for none, it is told to retry, so that one case never has two sessions.
  std::mutex opening_mutex_;
  std::set<std::string> opening_cases_;
};

}  // namespace vpm::service
