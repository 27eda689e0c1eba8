#include "server/service/vpm_server.h"

#include "server/cases/open_case_store.h"
#include "server/common/prefix_status.h"
#include "server/common/read_text_file.h"
#include "server/service/users_file.h"
#include "server/service/loopback_address.h"

#include <cstdio>
#include <cstdlib>
#include <filesystem>
#include <random>

#include <grpcpp/ext/proto_server_reflection_plugin.h>
#include <grpcpp/health_check_service_interface.h>

namespace vpm::service {
namespace {

Result<std::shared_ptr<grpc::ServerCredentials>> MakeCredentials(const ServerOptions& o) {
  if (o.tls_cert.empty() && o.tls_key.empty()) {
    if (!o.tls_client_ca.empty()) {
      return absl::InvalidArgumentError("--tls-client-ca needs --tls-cert and --tls-key");
    }
    return grpc::InsecureServerCredentials();
  }
  if (o.tls_cert.empty() || o.tls_key.empty()) {
    return absl::InvalidArgumentError("TLS needs both --tls-cert and --tls-key");
  }
  grpc::SslServerCredentialsOptions ssl;
  ASSIGN_OR_RETURN(std::string cert, ReadTextFile(o.tls_cert, "--tls-cert"));
  ASSIGN_OR_RETURN(std::string key, ReadTextFile(o.tls_key, "--tls-key"));
  ssl.pem_key_cert_pairs.push_back({key, cert});
  if (!o.tls_client_ca.empty()) {
    ASSIGN_OR_RETURN(ssl.pem_root_certs, ReadTextFile(o.tls_client_ca, "--tls-client-ca"));
    ssl.client_certificate_request = GRPC_SSL_REQUEST_AND_REQUIRE_CLIENT_CERTIFICATE_AND_VERIFY;
  }
  return grpc::SslServerCredentials(ssl);
}

// The users of --users, --token / --token-file / VPM_TOKEN, or --no-auth.
Result<TokenAuth> MakeAuth(const ServerOptions& o) {
  TokenAuth::Options auth;
  auth.disabled = o.no_auth;
  auth.token = o.token;
  if (!o.token_file.empty()) {
    if (!o.token.empty()) {
      return absl::InvalidArgumentError("give one of --token and --token-file, not both");
    }
    ASSIGN_OR_RETURN(std::string text, ReadTextFile(o.token_file, "--token-file"));
    const size_t first = text.find_first_not_of(" \t\r\n");
    const size_t last = text.find_last_not_of(" \t\r\n");
    if (first == std::string::npos) {
      return absl::InvalidArgumentError(StrCat("--token-file ", o.token_file, ": empty"));
    }
    auth.token = text.substr(first, last - first + 1);
  }
  if (!o.users_file.empty()) {
    ASSIGN_OR_RETURN(auth.users, ReadUsersFile(o.users_file));
  }
  return TokenAuth::Create(auth);
}

// The case store of --state (PostgreSQL) or else --state-dir (SQLite; the
// folder is created, and keeps uploads for cases either way); null without
// either. The error names the flag and what is
// wrong, so that the server says so at start.
Result<std::unique_ptr<cases::CaseStore>> OpenCaseStore(const ServerOptions& o) {
  if (!o.state_dir.empty()) {
    std::error_code error;
    std::filesystem::create_directories(o.state_dir, error);
    if (error) {
      return absl::FailedPreconditionError(
          StrCat("--state-dir ", o.state_dir, ": cannot create it (", error.message(), ")"));
    }
  }
  if (!o.state_url.empty()) return cases::OpenPostgresCaseStore(o.state_url);
  if (o.state_dir.empty()) return std::unique_ptr<cases::CaseStore>();
  Result<std::unique_ptr<cases::CaseStore>> store =
      cases::OpenSqliteCaseStore(std::filesystem::path(o.state_dir) / "cases.sqlite");
  if (!store.ok()) return PrefixStatus(store.status(), StrCat("--state-dir ", o.state_dir));
  return store;
}

// The PACS gateway of --pacs, --pacs-cache, --pacs-cache-bytes and
// --pacs-audit-log; null without --pacs.
Result<std::unique_ptr<pacs::PacsGateway>> MakePacsGateway(const ServerOptions& o) {
  if (o.pacs_file.empty()) {
    if (!o.pacs_cache.empty() || !o.pacs_audit_log.empty() || !o.dicom_listen.empty()) {
      return absl::InvalidArgumentError(
          "--pacs-cache, --pacs-audit-log and --dicom-listen need --pacs FILE");
    }
    return std::unique_ptr<pacs::PacsGateway>();
  }
  pacs::PacsGateway::Options options;
  ASSIGN_OR_RETURN(options.endpoints, pacs::ReadPacsEndpoints(o.pacs_file));
  options.audit_log = o.pacs_audit_log;
  options.cache.max_bytes = o.pacs_cache_bytes;
  if (o.pacs_cache.empty()) {
    const char* tmp = std::getenv("TMPDIR");
    std::string pattern = StrCat(tmp != nullptr && *tmp != '\0' ? tmp : "/tmp", "/vpm-pacs-cache-XXXXXX");
    if (::mkdtemp(pattern.data()) == nullptr) {
      return absl::InvalidArgumentError("--pacs: cannot make a temporary cache folder (give --pacs-cache)");
    }
    options.cache.root = pattern;
    options.cache.remove_root_on_destroy = true;
  } else {
    options.cache.root = o.pacs_cache;
  }
  if (!o.dicom_listen.empty()) {
    Result<pacs::DimseAddress> address = pacs::ParseDimseAddress(o.dicom_listen);
    if (!address.ok()) return PrefixStatus(address.status(), "--dicom-listen");
    options.listen = {.enabled = true,
                      .address = *address,
                      // Kept across restarts with --state-dir; else beside the cache.
                      .store_root = o.state_dir.empty()
                                        ? options.cache.root / ".received"
                                        : std::filesystem::path(o.state_dir) / "dicom-received",
                      .store_bytes = o.dicom_store_bytes,
                      .max_associations = static_cast<int>(o.dicom_max_associations),
                      .max_instance_bytes = o.dicom_max_instance_bytes};
  }
  return pacs::PacsGateway::Create(std::move(options));
}

// 8 hex digits from the OS's random source.
std::string RandomIdTag() {
  std::random_device random;
  char tag[9];
  std::snprintf(tag, sizeof tag, "%08x", static_cast<unsigned>(random()));
  return tag;
}

}  // namespace

Result<std::unique_ptr<VpmServer>> VpmServer::Create(const ServerOptions& options,
                                                     const gpu::GpuContext* gpu) {
  std::unique_ptr<VpmServer> s(new VpmServer());
  s->options_ = options;
  s->gpu_ = gpu;
  RETURN_IF_ERROR(s->Start());
  return s;
}

Status VpmServer::CreateVolumeStore() {
  const ServerOptions& o = options_;
  VolumeStore::Options volume_options;
  volume_options.context = gpu_;
  volume_options.data_root = o.data_root;
  volume_options.max_volumes = o.max_volumes;
  volume_options.max_bytes = o.max_total_volume_bytes;
  volume_options.max_volumes_per_owner = o.max_volumes_per_user;
  volume_options.read_limits.max_volume_bytes = o.max_volume_bytes;
  volume_options.on_change = [m = metrics_.get()](int64_t bytes, int64_t count) {
    m->Volumes(bytes, count);
  };
  id_tag_ = RandomIdTag();
  volume_options.id_prefix = StrCat("vol-", id_tag_, "-");
  volume_options.on_evict = [this](const std::string& id) {
    metrics_->VolumeEvicted();
    if (meshes_) meshes_->ForgetVolume(id);
  };
  ASSIGN_OR_RETURN(pacs_, MakePacsGateway(o));
  if (pacs_) {
    volume_options.read_pacs = [p = pacs_.get(), limits = volume_options.read_limits](
                                   std::string_view source, const std::string& user,
                                   const ProgressFn& progress, const CancelToken& cancel) {
      return p->LoadSeries(user, source, limits, progress, cancel);
    };
    volume_options.on_pacs_reuse = [p = pacs_.get()](std::string_view source,
                                                     const std::string& user) {
      p->RecordHeld(user, source);
    };
  }
  ASSIGN_OR_RETURN(volumes_, VolumeStore::Create(volume_options));
  return absl::OkStatus();
}

Status VpmServer::CreateSessionManager() {
  const ServerOptions& o = options_;
  SessionManager::Options session_options;
  session_options.context = gpu_;
  session_options.max_sessions = o.max_sessions;
  session_options.idle_session_s = o.idle_session_s;
  session_options.idle_watched_session_s = o.idle_watched_session_s;
  session_options.session.still_delay_ms = o.still_delay_ms;
  // Refinement without asking: on the request pool, in a lane of its own,
  // uncapped (the server's work for an admitted grab), ended by the
  // session's close.
  if (o.refine_on_grab) {
    session_options.session.refine = [this](std::weak_ptr<Session> session, std::string mesh_id,
                                            glm::dvec3 point_mm, CancelToken cancel) {
      Job job;
      job.lane = "refine";
      job.capped = false;
      job.run = [this, session, mesh_id, point_mm, cancel] {
        Result<std::shared_ptr<const MeshEntry>> refined =
            meshes_->Refine(mesh_id, point_mm, cancel);
        if (auto s = session.lock()) s->OfferRefinedMesh(std::move(refined));
      };
      job.drop = [session] {
        if (auto s = session.lock()) {
          s->OfferRefinedMesh(absl::UnavailableError("the server is stopping"));
        }
      };
      if (Status queued = request_pool_->Submit(std::move(job)); !queued.ok()) {
        if (auto s = session.lock()) s->OfferRefinedMesh(queued);
      }
    };
  }
  session_options.max_sessions_per_user = o.max_sessions_per_user;
  session_options.max_meshes_per_user = o.max_meshes_per_user;
  session_options.on_change = [m = metrics_.get()](
                                  int64_t open, const std::map<std::string, int64_t>& per_user) {
    m->Sessions(open, per_user);
  };
  session_options.id_prefix = StrCat("ses-", id_tag_, "-");
  ASSIGN_OR_RETURN(sessions_, SessionManager::Create(session_options));
  return absl::OkStatus();
}

void VpmServer::FillContext() {
  const ServerOptions& o = options_;
  context_.options = o;
  context_.gpu = gpu_;
  context_.auth = &*auth_;
  context_.volumes = volumes_.get();
  context_.meshes = meshes_.get();
  context_.sessions = sessions_.get();
  context_.metrics = metrics_.get();
  context_.render_pool = render_pool_.get();
  context_.request_pool = request_pool_.get();
  context_.streams = streams_.get();
  context_.upload_memory = upload_memory_.get();
  context_.upload_spool = upload_spool_.get();
  context_.load_progress = load_progress_.get();
  context_.pacs = pacs_.get();
  context_.cases = cases_.get();
  context_.blobs = blobs_ ? &*blobs_ : nullptr;
}

Status VpmServer::Listen(const std::shared_ptr<grpc::ServerCredentials>& credentials) {
  const ServerOptions& o = options_;
  grpc::EnableDefaultHealthCheckService(true);
  grpc::reflection::InitProtoReflectionServerBuilderPlugin();
  grpc::ServerBuilder builder;
  builder.AddListeningPort(o.listen, credentials, &port_);
  builder.RegisterService(service_.get());
  builder.SetMaxReceiveMessageSize(o.max_message_bytes);
  builder.SetMaxSendMessageSize(o.max_message_bytes);
  builder.AddChannelArgument(GRPC_ARG_KEEPALIVE_TIME_MS, o.keepalive_time_s * 1000);
  builder.AddChannelArgument(GRPC_ARG_KEEPALIVE_TIMEOUT_MS, o.keepalive_timeout_s * 1000);
  builder.AddChannelArgument(GRPC_ARG_KEEPALIVE_PERMIT_WITHOUT_CALLS, 1);
  builder.AddChannelArgument(GRPC_ARG_HTTP2_MIN_RECV_PING_INTERVAL_WITHOUT_DATA_MS, 5000);
  server_ = builder.BuildAndStart();
  if (!server_ || port_ == 0) {
    return absl::InvalidArgumentError(StrCat("--listen ", o.listen, ": cannot listen there"));
  }
  server_->GetHealthCheckService()->SetServingStatus(true);
  return absl::OkStatus();
}

Status VpmServer::Start() {
  const ServerOptions& o = options_;
  if (o.no_auth && !IsLoopbackAddress(o.listen)) {
    return absl::InvalidArgumentError(
        StrCat("--no-auth serves every caller without a token, so it listens on loopback only "
               "(127.0.0.1:PORT, [::1]:PORT, localhost:PORT or unix:PATH), not --listen ",
               o.listen, "; give --token (or VPM_TOKEN) to listen there"));
  }
  ASSIGN_OR_RETURN(TokenAuth auth, MakeAuth(o));
  auth_.emplace(std::move(auth));
  ASSIGN_OR_RETURN(auto credentials, MakeCredentials(o));
  ASSIGN_OR_RETURN(metrics_, ServiceMetrics::Create({o.metrics_listen}));
  gpu::GpuContext::Options gpu_options;
  gpu_options.device_selector = o.vulkan_device;
  if (gpu_ == nullptr) {
    ASSIGN_OR_RETURN(own_gpu_, gpu::GpuContext::Create(gpu_options));
    gpu_ = own_gpu_.get();
  }
  // A user's calls run on at most all workers but one of a pool (unless
  // told otherwise), so that another user's call always finds one free.
  auto queue_limits = [&o](int threads) {
    const int64_t running = o.max_running_per_user > 0
                                ? o.max_running_per_user
                                : std::max<int64_t>(1, threads - 1);
    return FairJobQueue::Limits{o.max_queued_per_user, o.max_queued, running};
  };
  ASSIGN_OR_RETURN(request_pool_, WorkerPool::Create({o.request_threads, "request",
                                                      queue_limits(o.request_threads)}));
  ASSIGN_OR_RETURN(render_pool_, WorkerPool::Create({o.render_threads, "render",
                                                     queue_limits(o.render_threads)}));
  RETURN_IF_ERROR(CreateVolumeStore());
  ASSIGN_OR_RETURN(cases_, OpenCaseStore(o));
  if (!o.state_dir.empty()) {
    ASSIGN_OR_RETURN(blobs_, cases::BlobStore::Open(o.state_dir));
  }
  ASSIGN_OR_RETURN(meshes_, MeshStore::Create({gpu_, o.max_meshes,
                                               [m = metrics_.get()](int64_t count) {
                                                 m->Meshes(count);
                                               },
                                               StrCat("mesh-", id_tag_, "-")}));
  RETURN_IF_ERROR(CreateSessionManager());
  streams_ = std::make_unique<StreamRegistry>(
      o.max_streams_per_user,
      [m = metrics_.get()](const std::string& user, int64_t n) { m->UserStreams(user, n); });
  metrics_->SetOpenStreamsSource([s = streams_.get()] { return s->open_streams(); });
  upload_memory_ = std::make_unique<ByteBudget>(o.max_upload_memory_bytes,
                                               o.max_upload_memory_bytes_per_user);
  upload_spool_ =
      std::make_unique<ByteBudget>(o.max_upload_spool_bytes, o.max_upload_spool_bytes_per_user);
  load_progress_ = std::make_unique<LoadProgressRegistry>();

  FillContext();
  service_ = std::make_unique<VpmService>(&context_);

  RETURN_IF_ERROR(Listen(credentials));
  reaper_ = std::thread([this] { ReapIdleSessions(); });
  return absl::OkStatus();
}

void VpmServer::ReapIdleSessions() {
  std::unique_lock lock(mutex_);
  while (!shut_down_) {
    stop_.wait_for(lock, std::chrono::seconds(1));
    if (shut_down_) break;
    lock.unlock();
    sessions_->EvictIdle();
    lock.lock();
  }
}

void VpmServer::BeginDrain() {
  context_.leaving = true;
  if (server_) server_->GetHealthCheckService()->SetServingStatus(false);
}

void VpmServer::Shutdown(std::chrono::milliseconds grace) {
  {
    std::lock_guard lock(mutex_);
    if (shut_down_) return;
    shut_down_ = true;
  }
  stop_.notify_all();
  if (pacs_) pacs_->StopListening();  // the DICOM node first: no new series while stopping
  if (server_) {
    context_.leaving = true;
    context_.draining = true;
    server_->GetHealthCheckService()->SetServingStatus(false);
    streams_->FinishAll(grpc::Status(grpc::UNAVAILABLE, "the server is shutting down"));
  }
  // Queued work runs until the grace period ends; what is left then is
  // dropped (each call answered UNAVAILABLE, counted), and a job still
  // running stops at its next poll, so that the process exits within the
  // grace period.
  const auto deadline = std::chrono::steady_clock::now() + grace;
  // Running work (a mesh build, a load) polls this and stops at the end of
  // the grace period, so that the pools' threads can be joined in time.
  context_.stop_work_at_ns =
      std::chrono::duration_cast<std::chrono::nanoseconds>(deadline.time_since_epoch()).count();
  if (render_pool_) render_pool_->Shutdown(deadline);
  if (request_pool_) request_pool_->Shutdown(deadline);
  if (server_) {
    const auto left = std::max(deadline - std::chrono::steady_clock::now(),
                               std::chrono::steady_clock::duration::zero());
    server_->Shutdown(std::chrono::system_clock::now() +
                      std::chrono::duration_cast<std::chrono::system_clock::duration>(left));
  }
  if (sessions_) sessions_->CloseAll();
  if (reaper_.joinable()) reaper_.join();
  // /metrics may still be scraped; the registry goes before the metrics.
  if (metrics_) metrics_->SetOpenStreamsSource(nullptr);
}

void VpmServer::Wait() {
  std::unique_lock lock(mutex_);
  stop_.wait(lock, [this] { return shut_down_; });
}

VpmServer::~VpmServer() { Shutdown(std::chrono::milliseconds(0)); }

}  // namespace vpm::service
