#include "server/pacs/dimse_address.h"

#include <charconv>

namespace vpm::pacs {

Status CheckAeTitle(std::string_view title) {
  if (title.empty() || title.size() > 16) {
    return absl::InvalidArgumentError("an AE title has 1 to 16 characters");
  }
  bool blank = true;
  for (char c : title) {
    if (c < 0x20 || c > 0x7e || c == '\\') {
      return absl::InvalidArgumentError("an AE title holds printable ASCII other than '\\' only");
    }
    blank = blank && c == ' ';
  }
  if (blank) return absl::InvalidArgumentError("an AE title is not all spaces");
  return absl::OkStatus();
}

Result<DimseAddress> ParseDimseAddress(std::string_view text) {
  const size_t at = text.find('@');
  const size_t colon = text.rfind(':');
  if (at == std::string_view::npos || colon == std::string_view::npos || colon < at) {
    return absl::InvalidArgumentError("a DICOM node is AET@HOST:PORT");
  }
  DimseAddress out{.ae_title = std::string(text.substr(0, at)),
                   .host = std::string(text.substr(at + 1, colon - at - 1))};
  RETURN_IF_ERROR(CheckAeTitle(out.ae_title));
  if (out.host.empty() || out.host.size() > 253 ||
      out.host.find_first_of(" /\\@") != std::string::npos) {
    return absl::InvalidArgumentError("a DICOM node's HOST is a host name or an IPv4 address");
  }
  const std::string_view port = text.substr(colon + 1);
  const auto [end, error] = std::from_chars(port.data(), port.data() + port.size(), out.port);
  if (error != std::errc() || end != port.data() + port.size() || out.port < 1 ||
      out.port > 65535) {
    return absl::InvalidArgumentError("a DICOM node's PORT is 1..65535");
  }
  return out;
}

}  // namespace vpm::pacs
