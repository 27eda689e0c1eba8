// The whole vpm-server process minus main(): the GPU context, the managers
// (each session has its own renderer), the worker pools, metrics, and the
// gRPC server with the vpm service, grpc.health.v1 and reflection. Members are declared in dependency
// order, so destruction runs in reverse.
#pragma once

#include <chrono>
#include <condition_variable>
#include <memory>
#include <optional>
#include <mutex>
#include <thread>

#include <grpcpp/grpcpp.h>

#include "server/gpu/gpu_context.h"
#include "server/service/server_options.h"
#include "server/service/service_context.h"
#include "server/service/vpm_service.h"

namespace vpm::service {

class VpmServer {
 public:
  // Builds everything and starts listening. Errors: InvalidArgument for bad
  // options (no token without --no-auth, unreadable TLS files, a listen
  // address that cannot be bound), and those of the GPU set-up.
  // `gpu`: a context owned by the caller (it must outlive the server), for
  // processes that run several servers (tests): Vulkan wants one context
  // per process. Null: the server makes its own.
  static Result<std::unique_ptr<VpmServer>> Create(const ServerOptions& options,
                                                   const gpu::GpuContext* gpu = nullptr);
  ~VpmServer();  // Shutdown(0)

  int port() const { return port_; }
  // Random per server start, in every volume, mesh and session id
  // ("vol-TAG-<32 hex>"): behind a balancer an id from one replica (or from before
  // a restart) is NOT_FOUND on another, never someone else's session.
  const std::string& id_tag() const { return id_tag_; }
  ServiceContext& context() { return context_; }
  ServiceMetrics& metrics() { return *metrics_; }

  // The first step of a graceful stop (--drain-s): health turns NOT_SERVING,
  // so balancers and readiness probes take the replica out of rotation,
  // while every call on what exists goes on (streams, events, renders) and
  // calls that would create volumes, meshes or sessions get UNAVAILABLE.
  void BeginDrain();
  // Stops: health turns NOT_SERVING, streams finish with UNAVAILABLE, new
  // calls are refused, and calls still running after `grace` are cancelled.
  // Idempotent.
  void Shutdown(std::chrono::milliseconds grace);
  void Wait();  // until Shutdown

 private:
  VpmServer() = default;
  Status Start();
  // Start's parts: the volume store (with the PACS loader when there is a
  // PACS), the session manager (with refinement on grab), the handlers'
  // context, and the gRPC server on --listen.
  Status CreateVolumeStore();
  Status CreateSessionManager();
  void FillContext();
  Status Listen(const std::shared_ptr<grpc::ServerCredentials>& credentials);
  void ReapIdleSessions();

  ServerOptions options_;
  std::unique_ptr<gpu::GpuContext> own_gpu_;
  const gpu::GpuContext* gpu_ = nullptr;
  std::unique_ptr<ServiceMetrics> metrics_;
  std::optional<TokenAuth> auth_;
  std::unique_ptr<WorkerPool> request_pool_;
  std::unique_ptr<WorkerPool> render_pool_;
  std::unique_ptr<pacs::PacsGateway> pacs_;  // before volumes_: their reads call it
  std::unique_ptr<cases::CaseStore> cases_;  // before sessions_: they write to it
  std::optional<cases::BlobStore> blobs_;    // --state-dir's uploads
  std::unique_ptr<VolumeStore> volumes_;
  std::unique_ptr<MeshStore> meshes_;
  std::unique_ptr<SessionManager> sessions_;
  std::unique_ptr<StreamRegistry> streams_;
  std::unique_ptr<ByteBudget> upload_memory_;
  std::unique_ptr<ByteBudget> upload_spool_;
  std::unique_ptr<LoadProgressRegistry> load_progress_;
  ServiceContext context_;
  std::unique_ptr<VpmService> service_;
  std::unique_ptr<grpc::Server> server_;
  int port_ = 0;
  std::string id_tag_;

  std::mutex mutex_;
  std::condition_variable stop_;
  bool shut_down_ = false;
  std::thread reaper_;
};

}  // namespace vpm::service
