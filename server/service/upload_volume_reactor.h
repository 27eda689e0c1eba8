// UploadVolume: a client stream whose first message is the header (file
// name, total size, SHA-256) and every later one a chunk of 64 KiB to 1 MiB
// (the last may be shorter). Size and chunk rules are checked as chunks
// arrive; the checksum at the end; the file is then read on the request pool
// (never in a callback) from a private temporary folder, which is removed.
// The volume belongs to the caller's user.
// Errors: UNAUTHENTICATED; INVALID_ARGUMENT for a missing or bad header, a
// bad chunk size, more bytes than declared, a truncated stream or a checksum
// mismatch; RESOURCE_EXHAUSTED past the upload or volume caps (the user's
// uploaded volumes included), the user's stream cap (an upload counts as a
// stream), a declared size over the user's share of upload memory, or, as
// chunks arrive, the memory budget for uploads in flight (server-wide and
// per user: bytes are reserved as they arrive, so an idle header holds
// nothing), or the spool's disk for uploads (server-wide and per user,
// reserved the same way, freed once the spooled file is removed);
// DEADLINE_EXCEEDED when no message arrives for --upload-idle-s,
// or when after that long the upload averages under
// --upload-min-bytes-per-s (a chunk a minute does not hold its bytes for
// ever).
//
// Lifetime and races: the reactor owns itself from Make until OnDone, and
// its idle timer and the completion task hold it too, so neither can touch
// freed memory. Finish is called once, never while a StartRead is being
// made (it is deferred to right after), and nothing starts after it: once
// the call is finished (cancelled, timed out, refused) a late read ends
// nothing and posts nothing.
#pragma once

#include <chrono>
#include <filesystem>
#include <memory>
#include <mutex>
#include <optional>
#include <string>
#include <vector>

#include <grpcpp/grpcpp.h>

#include "server/service/service_context.h"
#include "server/common/sha256.h"
#include "vpm/v3/vpm.pb.h"

namespace vpm::service {

inline constexpr int64_t kMinUploadChunkBytes = 64 << 10;
inline constexpr int64_t kMaxUploadChunkBytes = 1 << 20;

class UploadVolumeReactor : public grpc::ServerReadReactor<v3::UploadVolumeRequest>,
                            public std::enable_shared_from_this<UploadVolumeReactor> {
 public:
  static UploadVolumeReactor* Make(ServiceContext* service, grpc::CallbackServerContext* context,
                                   v3::VolumeInfo* response);

  void OnReadDone(bool ok) override;
  void OnCancel() override;
  void OnDone() override;

 private:
  UploadVolumeReactor(ServiceContext* service, grpc::CallbackServerContext* context,
                      v3::VolumeInfo* response);
  void Begin();
  // StartRead, unless the call is finished; a Finish decided meanwhile is
  // made right after.
  void ReadNext();
  // Re-arms itself until the call ends; fails the upload when idle.
  void ArmIdleTimer(std::chrono::milliseconds delay);
  void CheckIdle();
  Status TakeHeader(const v3::UploadVolumeRequest::Header& header);
  Status TakeChunk(const std::string& chunk);
  void Complete();  // on the request pool
  // With --state-dir: the verified file kept content-addressed (BlobStore)
  // and entry.upload_ref set, so that a case of this upload reopens.
  void KeepForCases(VolumeEntry& entry, const std::filesystem::path& file);
  void FinishOnce(const Status& status);

  ServiceContext* service_;
  grpc::CallbackServerContext* context_;
  v3::VolumeInfo* response_;
  std::string user_;  // the caller: the volume's owner (set in Begin)
  std::shared_ptr<UploadVolumeReactor> self_;  // from Make until OnDone
  bool slot_held_ = false;                     // a stream slot of this user
  int64_t reserved_bytes_ = 0;                 // in service_->upload_memory, under user_
  int64_t spooled_bytes_ = 0;                  // in service_->upload_spool, under user_
  v3::UploadVolumeRequest request_;
  bool have_header_ = false;
  std::string file_name_;
  int64_t total_bytes_ = 0;
  std::string sha256_hex_;
  std::vector<uint8_t> bytes_;
  Sha256 sha_;
  std::mutex mutex_;  // the fields below
  bool finished_ = false;
  bool completing_ = false;
  bool reading_ = false;                       // a StartRead is being made
  std::optional<grpc::Status> deferred_finish_;
  std::chrono::steady_clock::time_point last_message_at_;
  std::chrono::steady_clock::time_point started_at_;
  int64_t received_bytes_ = 0;  // chunk bytes taken so far
};

}  // namespace vpm::service
