#include "client/cli/export_dicom_command.h"

#include <cstdio>
#include <filesystem>
#include <memory>
#include <string>

#include "client/common/proto_json.h"
#include "client/cli/server_flags.h"
#include "server/common/write_file.h"

namespace vpm::cli {
namespace {

struct ExportDicomArgs {
  std::string session, to, out_dir, description;
  bool json = false;
};

// A streamed file's name must be one of the two folders' plain names: the
// server's answer never writes outside DIR.
Result<std::filesystem::path> ExportFileIn(const std::filesystem::path& dir, const std::string& name) {
  const size_t slash = name.find('/');
  const std::string folder = name.substr(0, slash);
  const std::string file = slash == std::string::npos ? "" : name.substr(slash + 1);
  if ((folder != "derived" && folder != "capture") || file.empty() ||
      file.find_first_of("/\\") != std::string::npos || file.starts_with(".")) {
    return absl::InternalError(StrCat("the server sent a file named '", name.substr(0, 80), "'"));
  }
  return dir / folder / file;
}

Status ExportDicom(const ServerConnection& s, const ExportDicomArgs& a) {
  if (a.to.empty() && a.out_dir.empty()) {
    return absl::InvalidArgumentError("export-dicom: --to pacs:NAME or --out-dir DIR");
  }
  v3::ExportDicomRequest request;
  request.set_session_id(a.session);
  request.set_series_description(a.description);
  if (!a.to.empty()) {
    if (!a.to.starts_with("pacs:") || a.to.size() == 5) {
      return absl::InvalidArgumentError("--to: pacs:ENDPOINT (an endpoint of the server's --pacs)");
    }
    request.set_endpoint(a.to.substr(5));
  }
  const std::filesystem::path dir(a.out_dir);
  if (a.to.empty()) {
    std::error_code error;
    for (const char* sub : {"derived", "capture"}) {
      std::filesystem::create_directories(dir / sub, error);
      if (error) return absl::InvalidArgumentError(StrCat("--out-dir ", a.out_dir, ": ", error.message()));
    }
  }
  auto context = s.Context(/*streaming=*/true);
  auto reader = s.stub().ExportDicom(context.get(), request);
  v3::ExportDicomPart part;
  v3::ExportDicomSummary summary;
  int64_t files = 0;
  std::string last_stage;
  while (reader->Read(&part)) {
    if (part.has_summary()) summary = part.summary();
    if (!part.stage().empty() && !a.json) {
      std::fprintf(stderr, "\r%-8s %3.0f%%", part.stage().c_str(), 100.0 * part.fraction());
      last_stage = part.stage();
    }
    if (!part.file_name().empty()) {
      ASSIGN_OR_RETURN(const std::filesystem::path path, ExportFileIn(dir, part.file_name()));
      RETURN_IF_ERROR(WriteFile(path.string(), part.data()));
      ++files;
    }
  }
  if (!last_stage.empty()) std::fprintf(stderr, "\n");
  RETURN_IF_ERROR(FromGrpc(reader->Finish()));
  if (a.json) {
    PrintJson({{"study_uid", summary.study_uid()},
               {"derived_series_uid", summary.derived_series_uid()},
               {"capture_series_uid", summary.capture_series_uid()},
               {"instances", summary.instances()},
               {"endpoint", summary.endpoint()},
               {"out_dir", a.to.empty() ? a.out_dir : ""},
               {"series_description", summary.series_description()},
               {"max_displacement_mm", summary.max_displacement_mm()},
               {"bytes", summary.bytes()}});
    return absl::OkStatus();
  }
  std::printf("%s \"%s\": %d instances (%.1f MB), derived series %s, secondary capture %s, study %s\n",
              a.to.empty() ? StrCat("wrote ", files, " files under ", a.out_dir).c_str()
                           : StrCat("sent to ", a.to).c_str(),
              summary.series_description().c_str(), summary.instances(),
              double(summary.bytes()) / 1e6, summary.derived_series_uid().c_str(),
              summary.capture_series_uid().c_str(), summary.study_uid().c_str());
  return absl::OkStatus();
}

}  // namespace

void AddExportDicomCommand(CLI::App& app, const ServerFlags* flags, int* exit_code) {
  auto args = std::make_shared<ExportDicomArgs>();
  CLI::App* c = app.add_subcommand(
      "export-dicom",
      "server: a session's deformed volume as a derived DICOM series (+ its 3D view) in the "
      "source's study");
  c->add_option("--session", args->session, "session id")->required();
  auto* to = c->add_option("--to", args->to, "pacs:ENDPOINT: the server sends it (STOW-RS)");
  auto* out = c->add_option("--out-dir", args->out_dir,
                            "write DIR/derived/*.dcm and DIR/capture/*.dcm here");
  to->excludes(out);
  c->add_option("--description", args->description,
                "SeriesDescription (at most 64 characters; default says what was done)");
  c->add_flag("--json", args->json, "print JSON");
  c->callback(
      WithServer(flags, exit_code, [args](const ServerConnection& s) { return ExportDicom(s, *args); }));
}

}  // namespace vpm::cli
