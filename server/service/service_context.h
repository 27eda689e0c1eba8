// What every handler and reactor of the service reaches: the managers, the
// pools, the limits and the metrics. Owned by VpmServer; outlives every call.
#pragma once

#include <atomic>
#include <chrono>
#include <cstdint>
#include <limits>

#include "server/cases/blob_store.h"
#include "server/cases/case_store.h"
#include "server/pacs/pacs_gateway.h"
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
  ByteBudget* upload_spool = nullptr;   // bytes of uploads bound for the spool's disk
  pacs::PacsGateway* pacs = nullptr;    // null without --pacs
  cases::CaseStore* cases = nullptr;    // null without --state-dir or --state
  const cases::BlobStore* blobs = nullptr;  // uploads kept for cases; null without --state-dir
  // Health says NOT_SERVING (VpmServer::BeginDrain): calls on what exists go
  // on, calls that would create volumes, meshes or sessions are refused.
  std::atomic<bool> leaving{false};
  // Shutting down: new streams are refused too.
  LoadProgressRegistry* load_progress = nullptr;  // GetLoadProgress
  std::atomic<bool> draining{false};

  // When running work must stop (steady clock, ns since its epoch): the end
  // of the shutdown grace period once VpmServer::Shutdown has begun, never
  // before. Every call's CancelToken polls it (WorkAllowed).
  std::atomic<int64_t> stop_work_at_ns{std::numeric_limits<int64_t>::max()};

  // UNAVAILABLE once the grace period is over: a running build, load or
  // render returns at its next poll, so that the process exits in time.
  Status WorkAllowed() const {
    const int64_t now_ns = std::chrono::duration_cast<std::chrono::nanoseconds>(
                               std::chrono::steady_clock::now().time_since_epoch())
                               .count();
    if (now_ns < stop_work_at_ns.load(std::memory_order_relaxed)) return absl::OkStatus();
    return absl::UnavailableError("the server shut down before this call finished");
  }

  // A new stream (Interact, Watch, UploadVolume, ExportDicom) of `user`:
  // refused while shutting down, and while leaving when it creates state;
  // else a slot of the user's stream cap, which the caller releases when
  // the call is done.
  Status AdmitStream(const std::string& user, bool creates_state) const {
    if (draining) return absl::UnavailableError("the server is shutting down");
    if (creates_state) RETURN_IF_ERROR(AcceptingNewWork());
    return streams->Acquire(user);
  }

  // UNAVAILABLE while leaving, for the calls that create state.
  Status AcceptingNewWork() const {
    if (!leaving) return absl::OkStatus();
    return absl::UnavailableError(
        "this vpm-server replica is draining before it stops: it takes no new volumes, meshes "
        "or sessions; retry (a balancer sends the retry to another replica)");
  }
};

}  // namespace vpm::service
