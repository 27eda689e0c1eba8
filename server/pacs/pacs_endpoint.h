// The PACS a server may reach, from the file `vpm-server --pacs FILE` names.
#pragma once

#include <cstdint>
#include <filesystem>
#include <string>
#include <string_view>
#include <vector>

#include "server/common/status.h"

namespace vpm::pacs {

struct PacsEndpoint {
  std::string name;                // 1-64 of [A-Za-z0-9._-], not starting with '.'
  std::string dicomweb_url;        // http:// or https:// base, no trailing '/', no credentials
  // Or DICOM networking (DIMSE; dimse_client.h): the PACS's node, and the
  // AE title vpm calls it with (default "VPM"). Exactly one of the two.
  std::string dimse_ae_title;
  std::string dimse_host;
  int dimse_port = 0;
  std::string calling_ae_title = "VPM";
  // How a DIMSE endpoint brings a series: C-GET on vpm's own association
  // (default), or C-MOVE to `move_destination`, the AE title under which
  // the PACS knows vpm's --dicom-listen node (the instances arrive there).
  bool retrieve_by_move = false;
  std::string move_destination;
  // Or the series that nodes sent to vpm's --dicom-listen (C-STORE):
  // "receive": true. `receive_from`: the calling AE titles whose series it
  // shows (empty: every sender's).
  bool receive = false;
  std::vector<std::string> receive_from;
  std::string username;            // basic auth with `password` (both read at start)
  std::string password;            // secret: never logged, never in an error
  std::string bearer_token;        // secret, from bearer_token_file
  std::string ca_file;             // PEM bundle for https; empty: the system's
  std::vector<std::string> users;  // vpm users who may use it; "*": every signed-in user
  int64_t page_size = 100;         // studies per QIDO-RS page (a PACS may cap its answers lower)

  bool AllowsUser(std::string_view user) const;
};

// "PACS 'NAME'": how messages name an endpoint (never its URL's query or a
// secret).
std::string EndpointLabel(const PacsEndpoint& endpoint);

// Reads the endpoints file: a JSON list of objects
//   {"name": "orthanc", "dicomweb": "http://127.0.0.1:8042/dicom-web",
//    "username": "vpm", "password_file": "orthanc.pw",   (or "bearer_token_file")
//    "ca_file": "ca.pem", "users": ["alice", "bob"], "page_size": 100}
// or, for DICOM networking, {"name": "pacs", "dimse": "ORTHANC@10.0.0.5:4242",
//    "calling_aet": "VPM", "retrieve": "get" | "move", "move_destination": "VPM",
//    "users": [...]} (no credentials: DIMSE has none), or the series sent to
// vpm's own node, {"name": "inbox", "receive": true, "from": ["CT01"],
//    "users": [...]}.
// Relative file names are taken from the endpoints file's folder; a secret
// file's surrounding whitespace is dropped. Unknown keys, a missing name,
// URL or users list, a name given twice, credentials in the URL, both a
// password and a bearer token, or an unreadable or empty secret file are
// InvalidArgument naming the file, the entry and the key, never a secret's
// text.
Result<std::vector<PacsEndpoint>> ReadPacsEndpoints(const std::filesystem::path& path);

// The same from text (tests); `folder` resolves relative file names.
Result<std::vector<PacsEndpoint>> ParsePacsEndpoints(std::string_view text,
                                                     const std::filesystem::path& folder,
                                                     std::string_view file_label);

// OK for a valid endpoint name; InvalidArgument otherwise (not quoting it).
Status CheckEndpointName(std::string_view name);

}  // namespace vpm::pacs
