// A DICOM network node as "AET@HOST:PORT" (the endpoints file's "dimse"
// key, vpm-server --dicom-listen).
#pragma once

#include <string>
#include <string_view>

#include "server/common/status.h"

namespace vpm::pacs {

struct DimseAddress {
  std::string ae_title;  // 1-16 characters, no backslash or control character
  std::string host;      // a host name or IPv4 address
  int port = 0;          // 1..65535
};

// Parses "AET@HOST:PORT". InvalidArgument naming what is wrong (not
// quoting the text).
Result<DimseAddress> ParseDimseAddress(std::string_view text);

// OK for a valid AE title (1-16 characters of printable ASCII other than
// '\', not all spaces).
Status CheckAeTitle(std::string_view title);

}  // namespace vpm::pacs
