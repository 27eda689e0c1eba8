// Prometheus metrics (prometheus-cpp), served on --metrics-listen:
//   vpm_requests_total{method,code,user}        every finished call, by caller
//   vpm_request_errors_total{method,code,user}  the non-OK ones ("unauthenticated":
//                                               calls refused before a user was known)
//   vpm_frame_stage_ms{stage}               fem, warp, render, encode, queue, total
//   vpm_frames_total, vpm_frames_superseded_total
//   vpm_sessions, vpm_volumes, vpm_volume_bytes, vpm_meshes
//   vpm_user_sessions{user}, vpm_user_streams{user}  sessions owned; Interact, Watch, uploads
//   vpm_dropped_jobs_total{method,reason}  queued calls dropped: cancelled, deadline,
//                                          queue_full, shutdown, idle (uploads)
//   vpm_volumes_evicted_total               idle volumes evicted to make room
//   vpm_streams_opened_total, vpm_streams_closed_total (equal when idle)
//   vpm_open_streams                       frame streams registered now
//   vpm_unary_calls_in_flight{method}      unary calls started and not yet answered
//                                          (0 when idle: each is answered once)
//   vpm_upload_temp_files                  uploads' temporary files on disk now
//   vpm_process_threads, vpm_process_open_fds, vpm_process_resident_bytes
//                                          read from /proc/self at each scrape
#pragma once

#include <atomic>
#include <cstdint>
#include <functional>
#include <map>
#include <memory>
#include <mutex>
#include <set>
#include <string>

#include <prometheus/counter.h>
#include <prometheus/exposer.h>
#include <prometheus/gauge.h>
#include <prometheus/histogram.h>
#include <prometheus/registry.h>

#include "server/common/status.h"
#include "vpm/v3/vpm.pb.h"

namespace vpm::service {

class ServiceMetrics {
 public:
  struct Options {
    std::string listen;  // HOST:PORT for /metrics; empty: kept in process only
  };
  static Result<std::unique_ptr<ServiceMetrics>> Create(const Options& options);

  // `user`: the caller (empty: not authenticated).
  void Request(const std::string& method, const char* code, const std::string& user);
  void FrameSent(const v3::StageTimings& timings);
  void Superseded();
  void Sessions(int64_t open, const std::map<std::string, int64_t>& per_user);
  void UserStreams(const std::string& user, int64_t streams);
  // +1 when an upload's temporary file is made, -1 when it is removed.
  void TempFiles(int delta);
  // Where vpm_open_streams comes from (read at each scrape).
  void SetOpenStreamsSource(std::function<int64_t()> source);
  void Volumes(int64_t bytes, int64_t count);
  void Meshes(int64_t count);
  // A queued call dropped before it ran; reason "cancelled" or "deadline".
  void DroppedJob(const std::string& method, const std::string& reason);
  void VolumeEvicted();
  void StreamOpened();
  void StreamClosed();
  // A unary call started (+1) or was answered (-1).
  void UnaryInFlight(const char* method, int delta);

  // Counters for tests and the shutdown log.
  double streams_opened() const { return streams_opened_->Value(); }
  int64_t dropped_jobs() const { return dropped_total_.load(); }
  double volumes_evicted() const { return evicted_->Value(); }
  // Finished calls of `method` with status `code` ("OK", "DEADLINE_EXCEEDED", ...),
  // of every user, or of `user` when given.
  double requests(const std::string& method, const std::string& code,
                  const std::string& user = "") const;
  double streams_closed() const { return streams_closed_->Value(); }
  // Unary calls started and not yet answered, all methods.
  int64_t unary_in_flight() const { return unary_in_flight_total_.load(); }
  double superseded() const { return superseded_->Value(); }
  double frames() const { return frames_->Value(); }
  // The text exposition format, as /metrics serves it (gauges read at
  // scrape time refreshed first).
  std::string Scrape() const;
  // The port /metrics listens on (0 without one).
  int metrics_port() const;

 private:
  ServiceMetrics() = default;
  void Refresh() const;  // the gauges read at scrape time

  std::shared_ptr<prometheus::Registry> registry_;
  std::unique_ptr<prometheus::Exposer> exposer_;
  prometheus::Family<prometheus::Counter>* requests_ = nullptr;
  prometheus::Family<prometheus::Counter>* errors_ = nullptr;
  prometheus::Family<prometheus::Histogram>* stages_ = nullptr;
  prometheus::Counter* frames_ = nullptr;
  prometheus::Counter* superseded_ = nullptr;
  prometheus::Counter* streams_opened_ = nullptr;
  prometheus::Counter* streams_closed_ = nullptr;
  prometheus::Gauge* sessions_ = nullptr;
  prometheus::Gauge* volumes_ = nullptr;
  prometheus::Gauge* volume_bytes_ = nullptr;
  prometheus::Gauge* meshes_ = nullptr;
  prometheus::Family<prometheus::Counter>* dropped_ = nullptr;
  prometheus::Counter* evicted_ = nullptr;
  std::atomic<int64_t> dropped_total_{0};
  prometheus::Family<prometheus::Gauge>* user_sessions_ = nullptr;
  prometheus::Family<prometheus::Gauge>* user_streams_ = nullptr;
  prometheus::Gauge* open_streams_ = nullptr;
  prometheus::Family<prometheus::Gauge>* unary_in_flight_ = nullptr;
  std::atomic<int64_t> unary_in_flight_total_{0};
  prometheus::Gauge* temp_files_ = nullptr;
  prometheus::Gauge* threads_ = nullptr;
  prometheus::Gauge* open_fds_ = nullptr;
  prometheus::Gauge* resident_bytes_ = nullptr;
  std::shared_ptr<prometheus::Collectable> refresher_;
  mutable std::mutex source_mutex_;
  std::function<int64_t()> open_streams_source_;
};

}  // namespace vpm::service
