#include "server/service/service_metrics.h"

#include <prometheus/collectable.h>
#include <prometheus/text_serializer.h>

#include "server/service/process_stats.h"

namespace vpm::service {
namespace {

// Registered with the exposer before the registry: brings the gauges read at
// scrape time up to date, and adds nothing itself.
class RefreshBeforeScrape : public prometheus::Collectable {
 public:
  explicit RefreshBeforeScrape(std::function<void()> refresh) : refresh_(std::move(refresh)) {}
  std::vector<prometheus::MetricFamily> Collect() const override {
    refresh_();
    return {};
  }

 private:
  std::function<void()> refresh_;
};

const char* UserLabel(const std::string& user) {
  return user.empty() ? "unauthenticated" : user.c_str();
}

const prometheus::Histogram::BucketBoundaries& StageBuckets() {
  static const prometheus::Histogram::BucketBoundaries buckets{
      0.5, 1, 2, 5, 10, 20, 35, 50, 75, 100, 150, 250, 500, 1000, 2500, 5000};
  return buckets;
}

}  // namespace

Result<std::unique_ptr<ServiceMetrics>> ServiceMetrics::Create(const Options& options) {
  std::unique_ptr<ServiceMetrics> m(new ServiceMetrics());
  m->registry_ = std::make_shared<prometheus::Registry>();
  auto& r = *m->registry_;
  m->requests_ = &prometheus::BuildCounter().Name("vpm_requests_total")
                      .Help("Finished calls by method and status code").Register(r);
  m->errors_ = &prometheus::BuildCounter().Name("vpm_request_errors_total")
                    .Help("Calls that finished with a non-OK code").Register(r);
  m->stages_ = &prometheus::BuildHistogram().Name("vpm_frame_stage_ms")
                    .Help("Server time per frame by stage, ms").Register(r);
  m->frames_ = &prometheus::BuildCounter().Name("vpm_frames_total")
                    .Help("Frames written to streams and unary renders").Register(r).Add({});
  m->superseded_ = &prometheus::BuildCounter().Name("vpm_frames_superseded_total")
                        .Help("Frames dropped because a newer one won").Register(r).Add({});
  m->streams_opened_ = &prometheus::BuildCounter().Name("vpm_streams_opened_total")
                            .Help("Interact, Watch and UploadVolume streams started").Register(r).Add({});
  m->streams_closed_ = &prometheus::BuildCounter().Name("vpm_streams_closed_total")
                            .Help("Streams whose resources were released").Register(r).Add({});
  m->sessions_ = &prometheus::BuildGauge().Name("vpm_sessions").Help("Open sessions").Register(r).Add({});
  m->volumes_ = &prometheus::BuildGauge().Name("vpm_volumes").Help("Volumes held").Register(r).Add({});
  m->meshes_ = &prometheus::BuildGauge().Name("vpm_meshes").Help("Meshes held").Register(r).Add({});
  m->dropped_ = &prometheus::BuildCounter()
                     .Name("vpm_dropped_jobs_total")
                     .Help("Queued calls dropped before they ran: cancelled, or past their deadline")
                     .Register(r);
  m->evicted_ = &prometheus::BuildCounter()
                     .Name("vpm_volumes_evicted_total")
                     .Help("Idle volumes evicted (least recently used) to make room; read again on use")
                     .Register(r)
                     .Add({});
  m->volume_bytes_ = &prometheus::BuildGauge().Name("vpm_volume_bytes")
                          .Help("Host and GPU bytes of the volumes held").Register(r).Add({});
  m->user_sessions_ = &prometheus::BuildGauge().Name("vpm_user_sessions")
                           .Help("Open sessions by owner").Register(r);
  m->user_streams_ = &prometheus::BuildGauge().Name("vpm_user_streams")
                          .Help("Interact and Watch streams by user").Register(r);
  m->open_streams_ = &prometheus::BuildGauge().Name("vpm_open_streams")
                          .Help("Frame streams registered now").Register(r).Add({});
  m->unary_in_flight_ = &prometheus::BuildGauge().Name("vpm_unary_calls_in_flight")
                             .Help("Unary calls started and not yet answered").Register(r);
  m->temp_files_ = &prometheus::BuildGauge().Name("vpm_upload_temp_files")
                        .Help("Temporary files of uploads on disk now").Register(r).Add({});
  m->threads_ = &prometheus::BuildGauge().Name("vpm_process_threads")
                     .Help("Threads of the server process").Register(r).Add({});
  m->open_fds_ = &prometheus::BuildGauge().Name("vpm_process_open_fds")
                      .Help("Open file descriptors of the server process").Register(r).Add({});
  m->resident_bytes_ = &prometheus::BuildGauge().Name("vpm_process_resident_bytes")
                            .Help("Resident memory of the server process, bytes").Register(r).Add({});
  ServiceMetrics* self = m.get();
  m->refresher_ = std::make_shared<RefreshBeforeScrape>([self] { self->Refresh(); });
  if (!options.listen.empty()) {
    try {
      m->exposer_ = std::make_unique<prometheus::Exposer>(options.listen);
    } catch (const std::exception& e) {
      return absl::InvalidArgumentError(
          StrCat("--metrics-listen ", options.listen, ": ", e.what()));
    }
    m->exposer_->RegisterCollectable(m->refresher_);
    m->exposer_->RegisterCollectable(m->registry_);
  }
  return m;
}

void ServiceMetrics::Request(const std::string& method, const char* code,
                             const std::string& user) {
  const prometheus::Labels labels{{"method", method}, {"code", code}, {"user", UserLabel(user)}};
  requests_->Add(labels).Increment();
  if (std::string_view(code) != "OK") errors_->Add(labels).Increment();
}

void ServiceMetrics::UnaryInFlight(const char* method, int delta) {
  unary_in_flight_->Add({{"method", method}}).Increment(delta);
  unary_in_flight_total_ += delta;
}

double ServiceMetrics::requests(const std::string& method, const std::string& code,
                                const std::string& user) const {
  double sum = 0;
  for (const prometheus::MetricFamily& family : requests_->Collect()) {
    for (const prometheus::ClientMetric& metric : family.metric) {
      int matched = 0;
      for (const prometheus::ClientMetric::Label& label : metric.label) {
        matched += (label.name == "method" && label.value == method) ||
                   (label.name == "code" && label.value == code) ||
                   (label.name == "user" && label.value == user);
      }
      if (matched == (user.empty() ? 2 : 3)) sum += metric.counter.value;
    }
  }
  return sum;
}

void ServiceMetrics::FrameSent(const v3::StageTimings& t) {
  frames_->Increment();
  for (auto [stage, ms] : {std::pair{"fem", t.fem_ms()}, std::pair{"warp", t.warp_ms()},
                           std::pair{"render", t.render_ms()}, std::pair{"encode", t.encode_ms()},
                           std::pair{"queue", t.queue_ms()}, std::pair{"total", t.total_ms()}}) {
    stages_->Add({{"stage", stage}}, StageBuckets()).Observe(ms);
  }
}

void ServiceMetrics::Superseded() { superseded_->Increment(); }
void ServiceMetrics::Sessions(int64_t open, const std::map<std::string, int64_t>& per_user) {
  sessions_->Set(double(open));
  for (const auto& [user, count] : per_user) {
    user_sessions_->Add({{"user", UserLabel(user)}}).Set(double(count));
  }
}
void ServiceMetrics::UserStreams(const std::string& user, int64_t streams) {
  user_streams_->Add({{"user", UserLabel(user)}}).Set(double(streams));
}
void ServiceMetrics::TempFiles(int delta) { temp_files_->Increment(delta); }
void ServiceMetrics::SetOpenStreamsSource(std::function<int64_t()> source) {
  std::lock_guard lock(source_mutex_);
  open_streams_source_ = std::move(source);
}
void ServiceMetrics::Refresh() const {
  const ProcessStats stats = ReadProcessStats();
  threads_->Set(double(stats.threads));
  open_fds_->Set(double(stats.open_fds));
  resident_bytes_->Set(double(stats.resident_bytes));
  std::lock_guard lock(source_mutex_);
  if (open_streams_source_) open_streams_->Set(double(open_streams_source_()));
}
void ServiceMetrics::Volumes(int64_t bytes, int64_t count) {
  volume_bytes_->Set(double(bytes));
  volumes_->Set(double(count));
}
void ServiceMetrics::Meshes(int64_t count) { meshes_->Set(double(count)); }
void ServiceMetrics::DroppedJob(const std::string& method, const std::string& reason) {
  dropped_->Add({{"method", method}, {"reason", reason}}).Increment();
  ++dropped_total_;
}
void ServiceMetrics::VolumeEvicted() { evicted_->Increment(); }
void ServiceMetrics::StreamOpened() { streams_opened_->Increment(); }
void ServiceMetrics::StreamClosed() { streams_closed_->Increment(); }

std::string ServiceMetrics::Scrape() const {
  Refresh();
  return prometheus::TextSerializer().Serialize(registry_->Collect());
}

int ServiceMetrics::metrics_port() const {
  if (!exposer_) return 0;
  auto ports = exposer_->GetListeningPorts();
  return ports.empty() ? 0 : ports.front();
}

}  // namespace vpm::service
