#include "server/io/read_file_bytes.h"

#include <algorithm>
#include <fstream>
#include <system_error>

namespace vpm {

Result<std::vector<uint8_t>> ReadFileBytes(const std::filesystem::path& path,
                                           const VolumeLimits& limits) {
  const std::string name = path.string();
  std::error_code ec;
  const auto status = std::filesystem::status(path, ec);
  if (ec || !std::filesystem::exists(status)) {
    return absl::NotFoundError(StrCat(name, ": no such file"));
  }
  if (!std::filesystem::is_regular_file(status)) {
    return absl::InvalidArgumentError(StrCat(name, ": not a regular file"));
  }
  const uintmax_t size = std::filesystem::file_size(path, ec);
  if (ec) return absl::InvalidArgumentError(StrCat(name, ": cannot get its size"));
  if (size > static_cast<uintmax_t>(limits.max_bytes)) {
    return absl::ResourceExhaustedError(StrCat(
        name, ": file of ", size, " bytes is over the cap of ", limits.max_bytes, " bytes"));
  }
  std::vector<uint8_t> bytes(static_cast<size_t>(size));
  RETURN_IF_ERROR(ReadFileRangeInto(path, 0, bytes, limits));
  return bytes;
}

Status ReadFileRangeInto(const std::filesystem::path& path, int64_t offset,
                         std::span<uint8_t> out, const VolumeLimits& limits) {
  const std::string name = path.string();
  std::ifstream in(path, std::ios::binary);
  if (!in) return absl::NotFoundError(StrCat(name, ": cannot open"));
  if (offset > 0) in.seekg(static_cast<std::streamoff>(offset));
  const uintmax_t size = out.size();
  // In chunks, so that a progress bar moves while a large file comes in.
  constexpr uintmax_t kChunk = uintmax_t{16} << 20;
  for (uintmax_t done = 0; done < size;) {
    const uintmax_t n = std::min(kChunk, size - done);
    in.read(reinterpret_cast<char*>(out.data() + done), static_cast<std::streamsize>(n));
    if (static_cast<uintmax_t>(in.gcount()) != n) {
      return absl::InvalidArgumentError(StrCat(name, ": read ", done + in.gcount(), " of ", size,
                                               " bytes (file changed?)"));
    }
    done += n;
    if (limits.read_progress != nullptr && *limits.read_progress) {
      (*limits.read_progress)(double(done) / double(size), "reading");
    }
  }
  return absl::OkStatus();
}

Result<std::vector<uint8_t>> ReadFilePrefix(const std::filesystem::path& path, int64_t count) {
  std::ifstream in(path, std::ios::binary);
  if (!in) return absl::NotFoundError(StrCat(path.string(), ": cannot open"));
  std::vector<uint8_t> bytes(static_cast<size_t>(std::max<int64_t>(count, 0)));
  in.read(reinterpret_cast<char*>(bytes.data()), static_cast<std::streamsize>(bytes.size()));
  bytes.resize(static_cast<size_t>(in.gcount()));
  return bytes;
}

DataFileLoader SiblingFileLoader(const std::filesystem::path& header_path,
                                 const VolumeLimits& limits) {
  return [folder = header_path.parent_path(),
          limits](std::string_view name) -> Result<std::vector<uint8_t>> {
    const std::filesystem::path relative(name);
    if (name.empty() || relative.is_absolute() || relative.has_root_name()) {
      return absl::InvalidArgumentError(StrCat(
          "data file \"", std::string(name), "\" must be a relative path next to the header"));
    }
    for (const auto& part : relative) {
      if (part == "..") {
        return absl::InvalidArgumentError(StrCat(
            "data file \"", std::string(name), "\" must not leave the header's folder (..)"));
      }
    }
    return ReadFileBytes(folder / relative, limits);
  };
}

}  // namespace vpm
