#include "server/pacs/dicom_part_writer.h"

#include <algorithm>
#include <cctype>
#include <cstdio>

namespace vpm::pacs {

DicomPartWriter::DicomPartWriter(std::filesystem::path folder, std::string what, int64_t max_bytes)
    : folder_(std::move(folder)), what_(std::move(what)), max_bytes_(max_bytes) {}

Status DicomPartWriter::Begin(const MultipartParser::Headers& headers) {
  auto type = headers.find("content-type");
  if (type != headers.end()) {
    std::string media = type->second.substr(0, type->second.find(';'));
    std::transform(media.begin(), media.end(), media.begin(),
                   [](unsigned char c) { return static_cast<char>(std::tolower(c)); });
    while (!media.empty() && media.back() == ' ') media.pop_back();
    if (media != "application/dicom" && media != "application/octet-stream") {
      return absl::InvalidArgumentError(StrCat(what_, ": part ", files_ + 1, " is '",
                                               media.substr(0, 60), "', not application/dicom"));
    }
  }
  char name[32];
  std::snprintf(name, sizeof(name), "%06lld.dcm", static_cast<long long>(files_ + 1));
  file_.open(folder_ / name, std::ios::binary | std::ios::trunc);
  if (!file_) return absl::InternalError("the PACS cache: cannot create a file");
  open_ = true;
  head_.clear();
  part_bytes_ = 0;
  return absl::OkStatus();
}

Status DicomPartWriter::Data(std::string_view chunk) {
  if (!open_) return absl::InternalError("multipart: data outside a part");
  if (head_.size() < 132) head_.append(chunk.substr(0, 132 - head_.size()));
  file_.write(chunk.data(), static_cast<std::streamsize>(chunk.size()));
  if (!file_) return absl::InternalError("the PACS cache: cannot write (disk full?)");
  part_bytes_ += static_cast<int64_t>(chunk.size());
  bytes_ += static_cast<int64_t>(chunk.size());
  if (bytes_ > max_bytes_) {
    return absl::ResourceExhaustedError(StrCat(
        what_, " is over ", max_bytes_, " bytes, the PACS cache's budget (--pacs-cache-bytes)"));
  }
  return absl::OkStatus();
}

Status DicomPartWriter::End() {
  file_.close();
  open_ = false;
  if (!file_) return absl::InternalError("the PACS cache: cannot write (disk full?)");
  if (head_.size() < 132 || head_.compare(128, 4, "DICM") != 0) {
    return absl::InvalidArgumentError(
        StrCat(what_, ": part ", files_ + 1, " (", part_bytes_, " bytes) is not a DICOM file"));
  }
  ++files_;
  return absl::OkStatus();
}

MultipartParser::Callbacks DicomPartWriter::Callbacks() {
  return {.part_begin = [this](const MultipartParser::Headers& h) { return Begin(h); },
          .part_data = [this](std::string_view chunk) { return Data(chunk); },
          .part_end = [this] { return End(); }};
}

}  // namespace vpm::pacs
