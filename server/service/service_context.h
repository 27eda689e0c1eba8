// What every handler and reactor of the service reaches: the managers, the
// pools, the limits and the metrics. Owned by VpmServer; outlives every call.
#pragma once

#include <atomic>

#include "server/raycast/volume_renderer.h"
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
  VolumeRenderer* renderer = nullptr;
  TokenAuth* auth = nullptr;
  VolumeStore* volumes = nullptr;
  MeshStore* meshes = nullptr;
  SessionManager* sessions = nullptr;
  ServiceMetrics* metrics = nullptr;
  WorkerPool* render_pool = nullptr;   // events and frames
  WorkerPool* request_pool = nullptr;  // unary work
  StreamRegistry* streams = nullptr;
  LoadProgressRegistry* load_progress = nullptr;  // GetLoadProgress
  std::atomic<bool> draining{false};
};

}  // namespace vpm::service
