// What every handler and reactor of the service reaches: the managers, the
// pools, the limits and the metrics. Owned by VpmServer; outlives every call.
#pragma once

#include <atomic>

#include "server/service/byte_budget.h"
#include "server/service/load_progress_registry.h"
#include "server/service/mesh_store.h"
#include "server/service/server_options.h"
#include "server/service/service_metrics.h"
#include "server/service/session_manager.h"
#include "server/service/stream_registry.h"
#include "server/service/token_auth.h"
#include "server/service/volume_store.h"
#include "server/service/worker_pool.h"

namespace vpm::service {

struct ServiceContext {
  ServerOptions options;
  const gpu::GpuContext* gpu = nullptr;
  TokenAuth* auth = nullptr;
  VolumeStore* volumes = nullptr;
  MeshStore* meshes = nullptr;
  SessionManager* sessions = nullptr;
  ServiceMetrics* metrics = nullptr;
  WorkerPool* render_pool = nullptr;   // events and frames
  WorkerPool* request_pool = nullptr;  // unary work
  StreamRegistry* streams = nullptr;
  ByteBudget* upload_memory = nullptr;  // bytes of uploads in flight
  // Health says NOT_SERVING (VpmServer::BeginDrain): calls on what exists go
  // on, calls that would create volumes, meshes or sessions are refused.
  std::atomic<bool> leaving{false};
  // Shutting down: new streams are refused too.
  LoadProgressRegistry* load_progress = nullptr;  // GetLoadProgress
  std::atomic<bool> draining{false};

  // UNAVAILABLE while leaving, for the calls that create state.
  Status AcceptingNewWork() const {
    if (!leaving) return absl::OkStatus();
    return absl::UnavailableError(
        "this vpm-server replica is draining before it stops: it takes no new volumes, meshes "
        "or sessions; retry (a balancer sends the retry to another replica)");
  }
};

}  // namespace vpm::service
