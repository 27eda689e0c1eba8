#include "server/service/upload_volume_reactor.h"

#include <cctype>
#include <filesystem>
#include <fstream>
#include <random>

#include "server/service/grpc_status.h"
#include "server/service/proto_convert.h"

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

UploadVolumeReactor::UploadVolumeReactor(ServiceContext* service,
                                         grpc::CallbackServerContext* context,
                                         v2::VolumeInfo* response)
    : service_(service), response_(response) {
  service_->metrics->StreamOpened();
  if (Status auth = service_->auth->Check(*context); !auth.ok()) {
    FinishOnce(auth);
    return;
  }
  if (Status accepting = service_->AcceptingNewWork(); !accepting.ok()) {
    FinishOnce(accepting);
    return;
  }
  StartRead(&request_);
}

Status UploadVolumeReactor::TakeHeader(const v2::UploadVolumeRequest::Header& header) {
  const std::string& name = header.file_name();
  if (name.empty() || name.find('/') != std::string::npos || name.find('\\') != std::string::npos ||
      name == "." || name == "..") {
    return absl::InvalidArgumentError("header.file_name: give a plain file name (no folders)");
  }
  if (!(EndsWith(name, ".nii") || EndsWith(name, ".nii.gz") || EndsWith(name, ".nrrd") ||
        EndsWith(name, ".mha"))) {
    return absl::InvalidArgumentError(
        StrCat("header.file_name: '", name, "' must end in .nii, .nii.gz, .nrrd or .mha "
               "(single-file formats)"));
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
  RETURN_IF_ERROR(service_->volumes->CheckRoom(0));
  file_name_ = name;
  total_bytes_ = header.total_bytes();
  sha256_hex_ = header.sha256_hex();
  for (char& c : sha256_hex_) c = static_cast<char>(std::tolower(static_cast<unsigned char>(c)));
  bytes_.reserve(static_cast<size_t>(total_bytes_));
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
  const auto* data = reinterpret_cast<const uint8_t*>(chunk.data());
  bytes_.insert(bytes_.end(), data, data + size);
  sha_.Update({data, chunk.size()});
  return absl::OkStatus();
}

void UploadVolumeReactor::OnReadDone(bool ok) {
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
      // From here Complete() owns the call: it alone finishes it (OnCancel
      // must not, or OnDone could free this while Complete runs).
      std::lock_guard lock(mutex_);
      completing_ = true;
    }
    if (!service_->request_pool->Post([this] { Complete(); })) {
      FinishOnce(absl::UnavailableError("the server is shutting down"));
    }
    return;
  }
  Status status;
  if (request_.has_header()) {
    status = have_header_ ? absl::InvalidArgumentError("header: sent twice")
                          : TakeHeader(request_.header());
  } else if (request_.part_case() == v2::UploadVolumeRequest::kChunk) {
    status = have_header_ ? TakeChunk(request_.chunk())
                          : absl::InvalidArgumentError("header: must come before any chunk");
  } else {
    status = absl::InvalidArgumentError("part: empty message (neither header nor chunk)");
  }
  if (!status.ok()) {
    FinishOnce(status);
    return;
  }
  StartRead(&request_);
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
    const fs::path dir = fs::temp_directory_path() /
                         StrCat("vpm-upload-", std::random_device{}(), "-", std::random_device{}());
    if (!fs::create_directory(dir, error)) {
      return absl::InternalError(StrCat("upload: cannot make a temporary folder: ", error.message()));
    }
    const fs::path path = dir / file_name_;
    Status status = [&]() -> Status {
      {
        std::ofstream file(path, std::ios::binary);
        file.write(reinterpret_cast<const char*>(bytes_.data()), std::streamsize(bytes_.size()));
        if (!file) return absl::InternalError("upload: cannot write the temporary file");
      }
      std::vector<uint8_t>().swap(bytes_);
      ASSIGN_OR_RETURN(std::shared_ptr<VolumeEntry> entry,
                       service_->volumes->AddFile(path, StrCat("upload:", file_name_)));
      FillVolumeInfo(*entry, response_);
      return absl::OkStatus();
    }();
    fs::remove_all(dir, error);
    // A file that no reader accepts is a malformed upload.
    if (!status.ok() && status.code() != absl::StatusCode::kResourceExhausted &&
        status.code() != absl::StatusCode::kInternal) {
      return absl::InvalidArgumentError(StrCat("upload '", file_name_, "': ", status.message()));
    }
    return status;
  };
  FinishOnce(run());
}

void UploadVolumeReactor::OnCancel() {
  {
    std::lock_guard lock(mutex_);
    if (completing_) return;
  }
  FinishOnce(absl::CancelledError("the client cancelled"));
}

void UploadVolumeReactor::FinishOnce(const Status& status) {
  {
    std::lock_guard lock(mutex_);
    if (finished_) return;
    finished_ = true;
  }
  const grpc::Status g = ToGrpcStatus(status);
  service_->metrics->Request("UploadVolume", StatusCodeName(g.error_code()));
  Finish(g);
}

void UploadVolumeReactor::OnDone() {
  service_->metrics->StreamClosed();
  delete this;
}

}  // namespace vpm::service
