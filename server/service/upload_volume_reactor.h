// UploadVolume: a client stream whose first message is the header (file
// name, total size, SHA-256) and every later one a chunk of 64 KiB to 1 MiB
// (the last may be shorter). Size and chunk rules are checked as chunks
// arrive; the checksum at the end; the file is then read on the request pool
// (never in a callback) from a private temporary folder, which is removed.
// Errors: UNAUTHENTICATED; INVALID_ARGUMENT for a missing or bad header, a
// bad chunk size, more bytes than declared, a truncated stream or a checksum
// mismatch; RESOURCE_EXHAUSTED past the upload or volume caps.
#pragma once

#include <mutex>
#include <string>
#include <vector>

#include <grpcpp/grpcpp.h>

#include "server/service/service_context.h"
#include "server/common/sha256.h"
#include "vpm/v2/vpm.pb.h"

namespace vpm::service {

inline constexpr int64_t kMinUploadChunkBytes = 64 << 10;
inline constexpr int64_t kMaxUploadChunkBytes = 1 << 20;

class UploadVolumeReactor : public grpc::ServerReadReactor<v2::UploadVolumeRequest> {
 public:
  UploadVolumeReactor(ServiceContext* service, grpc::CallbackServerContext* context,
                      v2::VolumeInfo* response);

  void OnReadDone(bool ok) override;
  void OnCancel() override;
  void OnDone() override;

 private:
  Status TakeHeader(const v2::UploadVolumeRequest::Header& header);
  Status TakeChunk(const std::string& chunk);
  void Complete();  // on the request pool
  void FinishOnce(const Status& status);

  ServiceContext* service_;
  v2::VolumeInfo* response_;
  std::string user_;  // the caller: the volume's owner
  v2::UploadVolumeRequest request_;
  bool have_header_ = false;
  std::string file_name_;
  int64_t total_bytes_ = 0;
  std::string sha256_hex_;
  std::vector<uint8_t> bytes_;
  Sha256 sha_;
  std::mutex mutex_;
  bool finished_ = false;
  bool completing_ = false;
};

}  // namespace vpm::service
