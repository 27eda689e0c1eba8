#include "client/cli/volume_commands.h"

#include <chrono>
#include <iomanip>
#include <iostream>
#include <optional>
#include <string>
#include <vector>

#include <nlohmann/json.hpp>

#include "client/common/command_status.h"
#include "client/common/progress_bar.h"
#include "client/cli/volume_flags.h"
#include "server/io/list_dicom_series.h"
#include "server/io/parse_dicom_source.h"
#include "server/io/read_volume.h"
#include "server/io/write_nifti.h"

namespace vpm::cli {
namespace {

nlohmann::json Vec(const glm::dvec3& v) { return {v.x, v.y, v.z}; }

nlohmann::json VolumeInfoJson(const Volume& v) {
  const VolumeGeometry& g = v.geometry();
  const std::array<glm::dvec3, 2> box = g.WorldBox();  // world LPS
  nlohmann::json landmarks = nlohmann::json::array();
  for (const Landmark& l : v.landmarks()) {
    landmarks.push_back({{"name", l.name},
                         {"position_mm", Vec(g.PhysicalToWorld(l.position_mm))},  // world LPS
                         {"description", l.description}});
  }
  return {
      {"source", v.source()},
      {"dims", {g.dims[0], g.dims[1], g.dims[2]}},
      {"spacing_mm", Vec(g.spacing_mm)},
      {"origin_lps_mm", Vec(g.origin_mm)},
      {"direction_columns_lps", {Vec(g.direction[0]), Vec(g.direction[1]), Vec(g.direction[2])}},
      {"extent_mm", Vec(g.extent_mm())},
      {"box_lps_mm", {Vec(box[0]), Vec(box[1])}},
      {"value_range", {v.min_value(), v.max_value()}},
      {"voxel_encoding", VoxelEncodingName(v.encoding())},
      {"value_bytes", v.value_bytes()},
      {"non_finite_voxels_replaced", v.non_finite_count()},
      {"notes", v.notes()},
      {"stacks", v.stacks()},
      {"stack", v.stack()},
      {"landmarks", landmarks}};
}

// The series of a DICOM folder source, or none for any other source.
std::vector<DicomSeriesSummary> DicomSeriesOf(const std::string& source) {
  const Result<std::optional<DicomSource>> dicom = ParseDicomSource(source);
  if (!dicom.ok() || !dicom->has_value()) return {};
  Result<std::vector<DicomSeriesSummary>> series =
      ListDicomSeries((*dicom)->folder, VolumeLimits{});
  return series.ok() ? *std::move(series) : std::vector<DicomSeriesSummary>{};
}

nlohmann::json SeriesJson(const std::vector<DicomSeriesSummary>& series) {
  nlohmann::json out = nlohmann::json::array();
  for (size_t n = 0; n < series.size(); ++n) {
    const DicomSeriesSummary& s = series[n];
    out.push_back({{"index", n + 1},
                   {"uid", s.uid},
                   {"number", s.series_number},
                   {"description", s.description},
                   {"modality", s.modality},
                   {"dims", {s.columns, s.rows, s.images}},
                   {"images", s.images},
                   {"stack", s.stack},
                   {"not_a_volume", s.not_a_volume_reason}});
  }
  return out;
}

void PrintSeries(const std::vector<DicomSeriesSummary>& series) {
  for (size_t n = 0; n < series.size(); ++n) {
    const DicomSeriesSummary& s = series[n];
    std::cout << (n == 0 ? "series      " : "            ") << n + 1 << ". " << s.uid << "  "
              << (s.modality.empty() ? "?" : s.modality) << "  \"" << s.description << "\"  "
              << s.columns << " x " << s.rows << " x " << s.images << " images"
              << (s.stack.empty() ? "" : "  (" + s.stack + ")")
              << (s.not_a_volume_reason.empty() ? ""
                                                : "  (" + s.not_a_volume_reason + ": never read)")
              << "\n";
  }
}

void PrintInfo(const Volume& v) {
  const VolumeGeometry& g = v.geometry();
  std::cout << std::fixed << std::setprecision(4);
  std::cout << "source      " << v.source() << "\n"
            << "dims        " << g.dims[0] << " x " << g.dims[1] << " x " << g.dims[2] << " ("
            << g.voxel_count() << " voxels)\n"
            << "spacing     " << g.spacing_mm.x << " " << g.spacing_mm.y << " " << g.spacing_mm.z
            << " mm\n"
            << "origin      " << g.origin_mm.x << " " << g.origin_mm.y << " " << g.origin_mm.z
            << " mm (world, LPS)\n";
  const std::array<glm::dvec3, 2> box = g.WorldBox();
  std::cout << "box         " << box[0].x << " " << box[0].y << " " << box[0].z << " .. "
            << box[1].x << " " << box[1].y << " " << box[1].z
            << " mm (world, LPS: where points go)\n";
  for (int c = 0; c < 3; ++c) {
    std::cout << (c == 0 ? "direction   " : "            ") << g.direction[c].x << " "
              << g.direction[c].y << " " << g.direction[c].z << "  (axis " << "ijk"[c] << ")\n";
  }
  std::cout << std::setprecision(1) << "values      " << v.min_value() << " .. " << v.max_value()
            << "\n";
  std::cout << "held as     " << VoxelEncodingName(v.encoding()) << ", " << v.value_bytes()
            << " bytes (host; the same again on the GPU)\n";
  for (const std::string& note : v.notes()) std::cout << "note        " << note << "\n";
  if (!v.stacks().empty()) {
    std::cout << "stack       " << v.stack() << " of " << v.stacks().size() << " ("
              << v.stacks()[static_cast<size_t>(v.stack() - 1)] << ")\n";
  }
  if (v.non_finite_count() > 0) {
    std::cout << "warning     " << v.non_finite_count()
              << " NaN/infinite voxels were replaced by the minimum\n";
  }
  for (const Landmark& l : v.landmarks()) {
    const glm::dvec3 w = g.PhysicalToWorld(l.position_mm);
    std::cout << "landmark    " << std::left << std::setw(22) << l.name << std::right
              << std::setprecision(2) << w.x << " " << w.y << " " << w.z << " mm (LPS)  "
              << l.description << "\n";
  }
}

// volume info: geometry, value range, landmarks and DICOM series.
void AddVolumeInfoCommand(CLI::App* volume, int* exit_code) {
  struct InfoArgs {
    std::string source;
    bool json = false;
    VolumeFlags volume_flags;
  };
  auto info_args = std::make_shared<InfoArgs>();
  CLI::App* info = volume->add_subcommand("info", "Print geometry, value range and landmarks");
  info->add_option("source", info_args->source,
                   "a file (.nii .nii.gz .nrrd .nhdr .mha .mhd), a DICOM folder, "
                   "phantom:NAME or raw:PATH?dims=..&type=..&spacing=..")
      ->required();
  info->add_flag("--json", info_args->json, "print JSON instead of text");
  AddVolumeFlags(info, &info_args->volume_flags);
  info->callback([info_args, exit_code] {
    Result<Volume> v = [&] {
      ProgressBar bar(StrCat("loading ", info_args->source),
                      ProgressWanted(info_args->volume_flags.progress));
      return ReadVolumeForCli(info_args->source, info_args->volume_flags, bar.Reporter());
    }();
    if (!v.ok()) {
      *exit_code = ExitWith(v.status());
      return;
    }
    const std::vector<DicomSeriesSummary> series = DicomSeriesOf(info_args->source);
    if (info_args->json) {
      nlohmann::json json = VolumeInfoJson(*v);
      if (!series.empty()) json["dicom_series"] = SeriesJson(series);
      // A note may name a file whose name is not UTF-8: replaced, never thrown.
      std::cout << json.dump(2, ' ', false, nlohmann::json::error_handler_t::replace) << "\n";
    } else {
      PrintInfo(*v);
      PrintSeries(series);
    }
  });
}

// volume export: any readable source as NIfTI, with progress.
void AddVolumeExportCommand(CLI::App* volume, int* exit_code) {
  struct ExportArgs {
    std::string source, out;
    VolumeFlags volume_flags;
  };
  auto export_args = std::make_shared<ExportArgs>();
  CLI::App* exp = volume->add_subcommand("export", "Write any readable source as NIfTI");
  exp->add_option("source", export_args->source, "as for `vpm volume info`")->required();
  exp->add_option("out", export_args->out, "output .nii or .nii.gz")->required();
  AddVolumeFlags(exp, &export_args->volume_flags);
  exp->callback([export_args, exit_code] {
    // The bar: reading 0..0.7, writing the rest.
    ProgressBar bar(StrCat("exporting ", export_args->source),
                    ProgressWanted(export_args->volume_flags.progress));
    const ProgressFn progress = bar.Reporter();
    auto v = ReadVolumeForCli(export_args->source, export_args->volume_flags,
                              SubProgress(progress, 0.0, 0.7));
    if (!v.ok()) {
      bar.Finish();
      *exit_code = ExitWith(v.status());
      return;
    }
    progress(0.7, "writing");
    const Status written = WriteNifti(*v, export_args->out);
    if (written.ok()) progress(1.0, "done");
    bar.Finish();
    *exit_code = ExitWith(written);
    if (*exit_code == 0) std::cout << "wrote " << export_args->out << "\n";
  });
}

}  // namespace

void AddVolumeCommands(CLI::App& app, int* exit_code) {
  CLI::App* volume = app.add_subcommand("volume", "Inspect and convert volumes");
  volume->require_subcommand(1);
  AddVolumeInfoCommand(volume, exit_code);
  AddVolumeExportCommand(volume, exit_code);
}

}  // namespace vpm::cli
