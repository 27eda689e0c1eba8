// What every handler and reactor of the service reaches: the managers, the
// pools, the limits and the metrics. Owned by VpmServer; outlives every call.
#pragma once

#include <atomic>
#include <cstdint>
#include <map>
#include <memory>
#include <mutex>
#include <string>

#include <grpcpp/server_context.h>

#include "server/render/volume_renderer.h"
#include "server/service/mesh_store.h"
#include "server/service/server_options.h"
#include "server/service/service_metrics.h"
#include "server/service/session_manager.h"
#include "server/service/token_auth.h"
#include "server/service/volume_store.h"
#include "server/service/worker_pool.h"

namespace vpm::service {

class FrameStream;

// Streams per client (peer address without the port) and every live frame
// stream, so that shutdown can finish them.
class StreamRegistry {
 public:
  explicit StreamRegistry(int64_t max_per_client) : max_per_client_(max_per_client) {}
  // ResourceExhausted past the per-client cap.
  Status Acquire(const std::string& peer);
  void Release(const std::string& peer);
  int64_t Register(std::weak_ptr<FrameStream> stream);
  void Unregister(int64_t token);
  // Finishes every registered stream with `status`.
  void FinishAll(const grpc::Status& status);
  int64_t open_streams() const;

  static std::string ClientOf(const std::string& peer);

 private:
  int64_t max_per_client_;
  mutable std::mutex mutex_;
  std::map<std::string, int64_t> per_client_;
  std::map<int64_t, std::weak_ptr<FrameStream>> streams_;
  int64_t next_token_ = 1;
};

struct ServiceContext {
  ServerOptions options;
  const gpu::GpuContext* gpu = nullptr;
  VolumeRenderer* renderer = nullptr;
  TokenAuth* auth = nullptr;
  VolumeStore* volumes = nullptr;
  MeshStore* meshes = nullptr;
  SessionManager* sessions = nullptr;
  ServiceMetrics* metrics = nullptr;
  WorkerPool* render_pool = nullptr;   // events and frames
  WorkerPool* request_pool = nullptr;  // unary work
  StreamRegistry* streams = nullptr;
  std::atomic<bool> draining{false};
};

}  // namespace vpm::service
