#include "server/service/upload_volume_reactor.h"

#include <algorithm>
#include <cctype>
#include <filesystem>
#include <cerrno>
#include <cstdio>
#include <cstdlib>
#include <cstring>

#include "server/common/write_file.h"
#include "server/service/grpc_status.h"
#include "server/service/proto_convert.h"
#include "server/service/resolve_data_path.h"

namespace vpm::service {
namespace {

bool EndsWith(const std::string& s, std::string_view suffix) {
  if (s.size() < suffix.size()) return false;
  for (size_t i = 0; i < suffix.size(); ++i) {
    if (std::tolower(static_cast<unsigned char>(s[s.size() - suffix.size() + i])) != suffix[i]) {
      return false;
    }
  }
  return true;
}

bool IsHex64(const std::string& s) {
  if (s.size() != 64) return false;
  for (char c : s) {
    if (!std::isxdigit(static_cast<unsigned char>(c))) return false;
  }
  return true;
}

}  // namespace

UploadVolumeReactor* UploadVolumeReactor::Make(ServiceContext* service,
                                               grpc::CallbackServerContext* context,
                                               v3::VolumeInfo* response) {
  std::shared_ptr<UploadVolumeReactor> reactor(new UploadVolumeReactor(service, context, response));
  reactor->self_ = reactor;
  reactor->Begin();
  return reactor.get();
}

UploadVolumeReactor::UploadVolumeReactor(ServiceContext* service,
                                         grpc::CallbackServerContext* context,
                                         v3::VolumeInfo* response)
    : service_(service), context_(context), response_(response) {
  service_->metrics->StreamOpened();
}

void UploadVolumeReactor::Begin() {
  // The caller's user (the volume's owner), draining, new work, then a
  // stream slot of this user (held until OnDone).
  Result<std::string> user = service_->auth->Authenticate(*context_);
  Status admitted = user.status();
  if (admitted.ok()) user_ = *std::move(user);
  if (admitted.ok()) admitted = service_->AdmitStream(user_, /*creates_state=*/true);
  if (!admitted.ok()) {
    FinishOnce(admitted);
    return;
  }
  slot_held_ = true;
  {
    std::lock_guard lock(mutex_);
    last_message_at_ = started_at_ = std::chrono::steady_clock::now();
  }
  ArmIdleTimer(std::chrono::milliseconds(int64_t(service_->options.upload_idle_s * 1000)));
  ReadNext();
}

void UploadVolumeReactor::ReadNext() {
  {
    std::lock_guard lock(mutex_);
    if (finished_) return;
    reading_ = true;
  }
  StartRead(&request_);
  std::optional<grpc::Status> deferred;
  {
    std::lock_guard lock(mutex_);
    reading_ = false;
    deferred.swap(deferred_finish_);
  }
  if (deferred) Finish(*deferred);
}

void UploadVolumeReactor::ArmIdleTimer(std::chrono::milliseconds delay) {
  if (service_->options.upload_idle_s <= 0) return;
  std::weak_ptr<UploadVolumeReactor> weak = weak_from_this();
  service_->request_pool->PostAfter(std::max(delay, std::chrono::milliseconds(1)), [weak] {
    if (auto self = weak.lock()) self->CheckIdle();
  });
}

void UploadVolumeReactor::CheckIdle() {
  const auto limit = std::chrono::milliseconds(int64_t(service_->options.upload_idle_s * 1000));
  std::chrono::steady_clock::duration idle;
  double elapsed_s = 0.0;
  int64_t received = 0;
  {
    std::lock_guard lock(mutex_);
    if (finished_ || completing_) return;
    const auto now = std::chrono::steady_clock::now();
    idle = now - last_message_at_;
    elapsed_s = std::chrono::duration<double>(now - started_at_).count();
    received = received_bytes_;
  }
  // Past its first --upload-idle-s, an upload must keep up an average of
  // --upload-min-bytes-per-s over the rest of its time.
  const double min_rate = service_->options.upload_min_bytes_per_s;
  const double grace_s = service_->options.upload_idle_s;
  if (min_rate > 0 && elapsed_s > grace_s && double(received) < min_rate * (elapsed_s - grace_s)) {
    service_->metrics->DroppedJob("UploadVolume", "idle");
    FinishOnce(absl::DeadlineExceededError(
        StrCat("upload: ", received, " bytes in ", int64_t(elapsed_s),
               " s, under the minimum average of ", int64_t(min_rate),
               " bytes a second (--upload-min-bytes-per-s); send chunks steadily")));
    return;
  }
  if (idle < limit) {
    ArmIdleTimer(std::chrono::duration_cast<std::chrono::milliseconds>(limit - idle));
    return;
  }
  service_->metrics->DroppedJob("UploadVolume", "idle");
  FinishOnce(absl::DeadlineExceededError(StrCat("upload: no message for ",
                                                service_->options.upload_idle_s,
                                                " s (--upload-idle-s); send chunks steadily")));
}

Status UploadVolumeReactor::TakeHeader(const v3::UploadVolumeRequest::Header& header) {
  const std::string& name = header.file_name();
  if (name.empty() || name.find('/') != std::string::npos || name.find('\\') != std::string::npos ||
      name == "." || name == "..") {
    return absl::InvalidArgumentError("header.file_name: give a plain file name (no folders)");
  }
  if (name.size() > kMaxPathComponentBytes) {  // the spool's file system takes no longer name
    return absl::InvalidArgumentError(StrCat("header.file_name: ", name.size(),
                                             " bytes; at most ", kMaxPathComponentBytes));
  }
  if (!(EndsWith(name, ".nii") || EndsWith(name, ".nii.gz") || EndsWith(name, ".nrrd") ||
        EndsWith(name, ".mha") || EndsWith(name, ".zip") || EndsWith(name, ".tar") ||
        EndsWith(name, ".tar.gz") || EndsWith(name, ".tgz"))) {
    return absl::InvalidArgumentError(
        StrCat("header.file_name: '", name, "' must end in .nii, .nii.gz, .nrrd or .mha "
               "(single-file formats), or .zip, .tar, .tar.gz or .tgz (a DICOM series)"));
  }
  if (header.total_bytes() <= 0) {
    return absl::InvalidArgumentError("header.total_bytes: must be positive");
  }
  if (header.total_bytes() > service_->options.max_upload_bytes) {
    return absl::ResourceExhaustedError(StrCat("header.total_bytes: ", header.total_bytes(),
                                               " is over the upload cap of ",
                                               service_->options.max_upload_bytes));
  }
  if (!IsHex64(header.sha256_hex())) {
    return absl::InvalidArgumentError("header.sha256_hex: must be 64 hexadecimal digits");
  }
  const int64_t share = service_->upload_memory->per_key_limit();
  if (share > 0 && header.total_bytes() > share) {
    return absl::ResourceExhaustedError(StrCat("header.total_bytes: ", header.total_bytes(),
                                               " is over your share of upload memory, ", share,
                                               " bytes (--max-upload-memory-bytes-per-user)"));
  }
  const int64_t spool_share = service_->upload_spool->per_key_limit();
  if (spool_share > 0 && header.total_bytes() > spool_share) {
    return absl::ResourceExhaustedError(StrCat(
        "header.total_bytes: ", header.total_bytes(), " is over your share of the upload spool, ",
        spool_share, " bytes (--max-upload-spool-bytes-per-user)"));
  }
  RETURN_IF_ERROR(service_->volumes->CheckRoom(0));
  RETURN_IF_ERROR(service_->volumes->CheckOwnerRoom(user_));
  // Memory is reserved as chunks arrive (TakeChunk), not here: a header
  // that sends nothing holds nothing.
  file_name_ = name;
  total_bytes_ = header.total_bytes();
  sha256_hex_ = header.sha256_hex();
  for (char& c : sha256_hex_) c = static_cast<char>(std::tolower(static_cast<unsigned char>(c)));
  bytes_.reserve(static_cast<size_t>(std::min<int64_t>(total_bytes_, kMaxUploadChunkBytes)));
  have_header_ = true;
  return absl::OkStatus();
}

Status UploadVolumeReactor::TakeChunk(const std::string& chunk) {
  const int64_t size = static_cast<int64_t>(chunk.size());
  const int64_t received = static_cast<int64_t>(bytes_.size());
  if (received + size > total_bytes_) {
    return absl::InvalidArgumentError(StrCat("chunk: ", received + size,
                                             " bytes received, more than header.total_bytes = ",
                                             total_bytes_));
  }
  const bool last = received + size == total_bytes_;
  if (size > kMaxUploadChunkBytes || (size < kMinUploadChunkBytes && !last)) {
    return absl::InvalidArgumentError(
        StrCat("chunk: ", size, " bytes; chunks are 64 KiB to 1 MiB (only the last may be shorter)"));
  }
  RETURN_IF_ERROR(service_->upload_memory->Reserve(user_, size, "upload in memory"));
  reserved_bytes_ += size;
  // Every byte taken is written to the spool when the upload ends: its disk
  // is reserved now, so that one user's uploads cannot fill it.
  RETURN_IF_ERROR(service_->upload_spool->Reserve(user_, size, "upload spool"));
  spooled_bytes_ += size;
  const auto* data = reinterpret_cast<const uint8_t*>(chunk.data());
  bytes_.insert(bytes_.end(), data, data + size);
  sha_.Update({data, chunk.size()});
  std::lock_guard lock(mutex_);
  received_bytes_ += size;
  return absl::OkStatus();
}

void UploadVolumeReactor::OnReadDone(bool ok) {
  {
    // A read that ends after the call was finished (cancelled, timed out)
    // decides nothing.
    std::lock_guard lock(mutex_);
    if (finished_) return;
    last_message_at_ = std::chrono::steady_clock::now();
  }
  if (!ok) {
    if (!have_header_) {
      FinishOnce(absl::InvalidArgumentError("header: the stream ended before a header"));
      return;
    }
    if (static_cast<int64_t>(bytes_.size()) != total_bytes_) {
      FinishOnce(absl::InvalidArgumentError(StrCat("truncated upload: ", bytes_.size(), " of ",
                                                   total_bytes_, " bytes received")));
      return;
    }
    {
      // From here Complete() owns the call: it alone finishes it, and the
      // task holds the reactor.
      std::lock_guard lock(mutex_);
      if (finished_) return;
      completing_ = true;
    }
    // A job dropped unrun (the server stopping) still answers the call:
    // OnCancel leaves a completing upload to this job.
    auto self = shared_from_this();
    Status queued = service_->request_pool->Submit(Job{
        .lane = "",
        .run = [self] { self->Complete(); },
        .drop = [self] {
          self->FinishOnce(absl::UnavailableError("the server shut down before the upload's turn"));
        },
        .capped = false});
    if (!queued.ok()) FinishOnce(queued);
    return;
  }
  Status status;
  if (request_.has_header()) {
    status = have_header_ ? absl::InvalidArgumentError("header: sent twice")
                          : TakeHeader(request_.header());
  } else if (request_.part_case() == v3::UploadVolumeRequest::kChunk) {
    status = have_header_ ? TakeChunk(request_.chunk())
                          : absl::InvalidArgumentError("header: must come before any chunk");
  } else {
    status = absl::InvalidArgumentError("part: empty message (neither header nor chunk)");
  }
  if (!status.ok()) {
    FinishOnce(status);
    return;
  }
  ReadNext();
}

void UploadVolumeReactor::Complete() {
  auto run = [&]() -> Status {
    const std::string actual = sha_.FinishHex();
    if (actual != sha256_hex_) {
      return absl::InvalidArgumentError(StrCat("header.sha256_hex: checksum mismatch, the bytes "
                                               "received hash to ", actual));
    }
    namespace fs = std::filesystem;
    std::error_code error;
    // mkdtemp: a fresh folder of mode 0700, so no other local user can read
    // or swap the patient's file while it is parsed.
    std::string pattern = (fs::temp_directory_path() / "vpm-upload-XXXXXX").string();
    if (mkdtemp(pattern.data()) == nullptr) {
      const int error = errno;
      const std::string why = StrCat("upload: the server cannot spool it: ", std::strerror(error));
      return error == ENOSPC || error == EDQUOT ? absl::ResourceExhaustedError(why)
                                                : absl::InternalError(why);
    }
    const fs::path dir = pattern;
    service_->metrics->TempFiles(+1);
    const fs::path path = dir / file_name_;
    Status status = [&]() -> Status {
      // A full spool (ENOSPC, EDQUOT, EFBIG) is the server's problem:
      // ResourceExhausted, never the user's malformed file.
      Status spooled = WriteFile(
          path, std::string_view(reinterpret_cast<const char*>(bytes_.data()), bytes_.size()));
      if (absl::IsResourceExhausted(spooled)) {
        return absl::ResourceExhaustedError(StrCat("upload: the server's upload spool is full (",
                                                   spooled.message(), "); try again later"));
      }
      RETURN_IF_ERROR(spooled);
      std::vector<uint8_t>().swap(bytes_);
      ASSIGN_OR_RETURN(std::shared_ptr<VolumeEntry> entry,
                       service_->volumes->AddFile(path, StrCat("upload:", file_name_), user_));
      KeepForCases(*entry, path);
      FillVolumeInfo(*entry, response_);
      return absl::OkStatus();
    }();
    fs::remove_all(dir, error);
    service_->metrics->TempFiles(-1);
    status = HideFolder(status, dir, "the upload");  // "case.nii: ...", no server path
    // A file that no reader accepts is a malformed upload.
    if (!status.ok() && status.code() != absl::StatusCode::kResourceExhausted &&
        status.code() != absl::StatusCode::kInternal) {
      return absl::InvalidArgumentError(StrCat("upload '", file_name_, "': ", status.message()));
    }
    return status;
  };
  FinishOnce(run());
}

void UploadVolumeReactor::KeepForCases(VolumeEntry& entry, const std::filesystem::path& file) {
  if (service_->blobs == nullptr) return;
  // Not kept (a full state disk): the upload stands, its case reopens only
  // while the upload is held (OpenCase says so).
  if (Status kept = service_->blobs->Put(sha256_hex_, file_name_, file); !kept.ok()) {
    std::fprintf(stderr, "vpm-server: upload %s not kept for its cases: %s\n", entry.id.c_str(),
                 kept.ToString().c_str());
    return;
  }
  entry.upload_ref = cases::BlobStore::Reference(sha256_hex_, file_name_);
}

void UploadVolumeReactor::OnCancel() {
  {
    std::lock_guard lock(mutex_);
    if (completing_) return;
  }
  FinishOnce(absl::CancelledError("the client cancelled"));
}

void UploadVolumeReactor::FinishOnce(const Status& status) {
  const grpc::Status g = ToGrpcStatus(status);
  {
    std::lock_guard lock(mutex_);
    if (finished_) return;
    finished_ = true;
    service_->metrics->Request("UploadVolume", StatusCodeName(g.error_code()), user_);
    if (reading_) {
      deferred_finish_ = g;  // ReadNext makes it once StartRead returns
      return;
    }
  }
  Finish(g);
}

void UploadVolumeReactor::OnDone() {
  if (reserved_bytes_ > 0) service_->upload_memory->Release(user_, reserved_bytes_);
  // Complete removed the spooled file before the call finished.
  if (spooled_bytes_ > 0) service_->upload_spool->Release(user_, spooled_bytes_);
  if (slot_held_) service_->streams->Release(user_);
  service_->metrics->StreamClosed();
  std::shared_ptr<UploadVolumeReactor> last = std::move(self_);  // may free this
}

}  // namespace vpm::service
