#include "client/cli/remote_volume_commands.h"

#include <filesystem>
#include <fstream>
#include <iterator>
#include <memory>
#include <vector>

#include "client/common/progress_bar.h"
#include "client/common/proto_json.h"
#include "client/cli/remote_pipeline.h"
#include "client/cli/server_flags.h"
#include "server/common/sha256.h"

namespace vpm::cli {
namespace {

namespace fs = std::filesystem;
using nlohmann::json;

Status Upload(const ServerConnection& server, const std::string& path) {
  std::ifstream file(path, std::ios::binary);
  if (!file) return absl::NotFoundError(StrCat(path, ": cannot read"));
  std::vector<uint8_t> bytes((std::istreambuf_iterator<char>(file)),
                             std::istreambuf_iterator<char>());
  auto context = server.Context();
  v3::VolumeInfo info;
  auto writer = server.stub().UploadVolume(context.get(), &info);
  v3::UploadVolumeRequest header;
  header.mutable_header()->set_file_name(fs::path(path).filename().string());
  header.mutable_header()->set_total_bytes(int64_t(bytes.size()));
  header.mutable_header()->set_sha256_hex(Sha256::HexOf(bytes));
  bool ok = writer->Write(header);
  constexpr size_t kChunk = 1 << 20;
  for (size_t at = 0; ok && at < bytes.size(); at += kChunk) {
    v3::UploadVolumeRequest chunk;
    chunk.set_chunk(bytes.data() + at, std::min(kChunk, bytes.size() - at));
    ok = writer->Write(chunk);
  }
  writer->WritesDone();
  RETURN_IF_ERROR(FromGrpc(writer->Finish()));
  PrintJson(VolumeJson(info));
  return absl::OkStatus();
}

}  // namespace

void AddRemoteVolumeCommands(CLI::App& app, const ServerFlags* flags, int* exit_code) {
  CLI::App* volume = app.get_subcommand("volume");
  struct LoadArgs {
    std::string source;
    bool progress = false;
  };
  auto load_args = std::make_shared<LoadArgs>();
  CLI::App* load = volume->add_subcommand(
      "load", "server: LoadVolume (data-root path, phantom: or pacs:), with its progress");
  load->add_option("SOURCE", load_args->source,
                   "path under the server's data root, phantom:NAME, or "
                   "pacs:ENDPOINT/STUDY_UID/SERIES_UID")->required();
  load->add_flag("--progress", load_args->progress,
                 "draw the progress bar (GetLoadProgress) even when stderr is not a terminal");
  load->callback(WithServer(flags, exit_code, [load_args](const ServerConnection& s) -> Status {
    ProgressBar bar(StrCat("loading ", load_args->source), ProgressWanted(load_args->progress));
    ASSIGN_OR_RETURN(v3::VolumeInfo info,
                     LoadVolumeOnServer(s, load_args->source, bar.Reporter()));
    bar.Finish();
    PrintJson(VolumeJson(info));
    return absl::OkStatus();
  }));
  auto file = std::make_shared<std::string>();
  CLI::App* upload = volume->add_subcommand("upload", "server: UploadVolume in 1 MiB chunks with SHA-256");
  upload->add_option("FILE", *file, ".nii, .nii.gz, .nrrd or .mha; or a DICOM series as .zip, .tar, .tar.gz, .tgz")->required();
  upload->callback(WithServer(flags, exit_code, [file](const ServerConnection& s) {
    return Upload(s, *file);
  }));
  volume->add_subcommand("list", "server: ListVolumes")
      ->callback(WithServer(flags, exit_code, [](const ServerConnection& s) -> Status {
        v3::ListVolumesResponse response;
        RETURN_IF_ERROR(FromGrpc(s.stub().ListVolumes(s.Context().get(), {}, &response)));
        json j = json::array();
        for (const auto& v : response.volumes()) j.push_back(VolumeJson(v));
        PrintJson(j);
        return absl::OkStatus();
      }));
  auto id = std::make_shared<std::string>();
  CLI::App* get = volume->add_subcommand("get", "server: GetVolume");
  get->add_option("ID", *id)->required();
  get->callback(WithServer(flags, exit_code, [id](const ServerConnection& s) -> Status {
    v3::GetVolumeRequest request;
    request.set_volume_id(*id);
    v3::VolumeInfo info;
    RETURN_IF_ERROR(FromGrpc(s.stub().GetVolume(s.Context().get(), request, &info)));
    PrintJson(VolumeJson(info));
    return absl::OkStatus();
  }));
  CLI::App* del = volume->add_subcommand("delete", "server: DeleteVolume");
  del->add_option("ID", *id)->required();
  del->callback(WithServer(flags, exit_code, [id](const ServerConnection& s) -> Status {
    v3::DeleteVolumeRequest request;
    request.set_volume_id(*id);
    v3::DeleteVolumeResponse response;
    return FromGrpc(s.stub().DeleteVolume(s.Context().get(), request, &response));
  }));
}

}  // namespace vpm::cli
