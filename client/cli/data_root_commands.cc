#include "client/cli/data_root_commands.h"

#include <cstdio>
#include <ctime>
#include <memory>
#include <string>

#include "client/cli/server_flags.h"
#include "client/common/proto_json.h"

namespace vpm::cli {
namespace {

using nlohmann::json;

const char* KindName(v3::DataRootEntry::Kind kind) {
  switch (kind) {
    case v3::DataRootEntry::FOLDER:
      return "folder";
    case v3::DataRootEntry::VOLUME_FILE:
      return "volume";
    case v3::DataRootEntry::DICOM_FOLDER:
      return "dicom";
    case v3::DataRootEntry::ARCHIVE:
      return "archive";
    case v3::DataRootEntry::OTHER_FILE:
      return "other";
    case v3::DataRootEntry::NOT_OPENABLE:
      return "unopenable";
    default:
      return "?";
  }
}

// "2024-05-01 12:34" in UTC.
std::string Modified(int64_t unix_ms) {
  const std::time_t t = static_cast<std::time_t>(unix_ms / 1000);
  std::tm tm{};
  gmtime_r(&t, &tm);
  char text[32];
  std::strftime(text, sizeof text, "%Y-%m-%d %H:%M", &tm);
  return text;
}

struct LsArgs {
  std::string path;
  bool json = false;
};

Status Ls(const ServerConnection& s, const LsArgs& a) {
  v3::ListDataRootRequest request;
  request.set_path(a.path);
  v3::ListDataRootResponse response;
  RETURN_IF_ERROR(FromGrpc(s.stub().ListDataRoot(s.Context().get(), request, &response)));
  if (a.json) {
    json entries = json::array();
    for (const v3::DataRootEntry& e : response.entries()) {
      entries.push_back({{"name", e.name()},
                         {"kind", KindName(e.kind())},
                         {"size_bytes", e.size_bytes()},
                         {"modified_unix_ms", e.modified_unix_ms()},
                         {"source", e.source()}});
    }
    PrintJson({{"path", response.path()}, {"entries", entries}, {"truncated", response.truncated()}});
    return absl::OkStatus();
  }
  std::printf("%-10s %12s %-16s %-40s %s\n", "KIND", "BYTES", "MODIFIED (UTC)", "NAME",
              "SOURCE (vpm volume load ...)");
  for (const v3::DataRootEntry& e : response.entries()) {
    const bool folder =
        e.kind() == v3::DataRootEntry::FOLDER || e.kind() == v3::DataRootEntry::DICOM_FOLDER;
    std::printf("%-10s %12lld %-16s %-40s %s\n", KindName(e.kind()),
                static_cast<long long>(e.size_bytes()), Modified(e.modified_unix_ms()).c_str(),
                (e.name() + (folder ? "/" : "")).c_str(), e.source().c_str());
  }
  if (response.truncated()) std::printf("(more entries than the server lists)\n");
  return absl::OkStatus();
}

}  // namespace

void AddDataRootCommands(CLI::App& app, const ServerFlags* flags, int* exit_code) {
  CLI::App* data = app.add_subcommand("data", "server: the files under the server's --data-root");
  data->require_subcommand(1);
  auto ls = std::make_shared<LsArgs>();
  CLI::App* l = data->add_subcommand("ls", "server: ListDataRoot, one folder of the data root");
  l->add_option("path", ls->path, "a folder relative to the data root (default: the root)");
  l->add_flag("--json", ls->json, "print JSON");
  l->callback(WithServer(flags, exit_code, [ls](const ServerConnection& c) { return Ls(c, *ls); }));
}

}  // namespace vpm::cli
