// The `vpm` command line as a user runs it: exit codes, messages, outputs.
#include <array>
#include <cstdio>
#include <filesystem>
#include <fstream>
#include <string>
#include <vector>

#include <gtest/gtest.h>
#include <nlohmann/json.hpp>

namespace {

struct CliRun {
  int exit_code;
  std::string output;  // stdout and stderr
};

CliRun Vpm(const std::string& args) {
  const std::string command = std::string(VPM_CLI) + " " + args + " 2>&1";
  FILE* pipe = popen(command.c_str(), "r");
  std::string output;
  std::array<char, 4096> buffer;
  while (size_t n = fread(buffer.data(), 1, buffer.size(), pipe)) output.append(buffer.data(), n);
  const int status = pclose(pipe);
  return {WIFEXITED(status) ? WEXITSTATUS(status) : -1, output};
}

std::string TempPath(const std::string& name) {
  return (std::filesystem::path(::testing::TempDir()) / name).string();
}

nlohmann::json ReadJson(const std::string& path) {
  std::ifstream file(path);
  return nlohmann::json::parse(file);
}

TEST(VpmCli, VolumeInfoPrintsGeometryAndLandmarks) {
  const CliRun run = Vpm("volume info 'phantom:abdomen?size=48' --json");
  ASSERT_EQ(run.exit_code, 0) << run.output;
  const auto info = nlohmann::json::parse(run.output.substr(run.output.find('{')));
  EXPECT_EQ(info["dims"], nlohmann::json({48, 48, 48}));
  bool has_artery = false;
  for (const auto& l : info["landmarks"]) has_artery |= l["name"] == "left_renal_artery";
  EXPECT_TRUE(has_artery);
}

TEST(VpmCli, ExportWritesNiftiThatReadsBackWithTheSameGeometry) {
  const std::string out = TempPath("exported.nii.gz");
  ASSERT_EQ(Vpm("volume export 'phantom:abdomen?dims=40,32,24' " + out).exit_code, 0);
  const CliRun run = Vpm("volume info " + out + " --json");
  ASSERT_EQ(run.exit_code, 0) << run.output;
  const auto info = nlohmann::json::parse(run.output.substr(run.output.find('{')));
  EXPECT_EQ(info["dims"], nlohmann::json({40, 32, 24}));
  EXPECT_NEAR(info["spacing_mm"][0].get<double>(), 380.0 / 40, 1e-4);
}

TEST(VpmCli, VolumeInfoSaysATiltedDicomSeriesWasResampledAndListsSeries) {
  const std::string folder = std::string(VPM_TEST_SOURCE_DIR) + "/tests/data/ct-philips-tilt";
  const CliRun run = Vpm("volume info '" + folder + "' --json");
  ASSERT_EQ(run.exit_code, 0) << run.output;
  const auto info = nlohmann::json::parse(run.output.substr(run.output.find('{')));
  // 512 rows grow to 600 to hold the 18.5 degree shear of 54 slices.
  EXPECT_EQ(info["dims"], nlohmann::json({512, 600, 54}));
  // The resampling note, and why the resampled values are float.
  ASSERT_EQ(info["notes"].size(), 2u) << info["notes"];
  EXPECT_NE(info["notes"].dump().find("gantry tilt 18.5 deg"), std::string::npos);
  EXPECT_NE(info["notes"].dump().find("stored as float32"), std::string::npos);
  EXPECT_EQ(info["voxel_encoding"], "float32");
  ASSERT_EQ(info["dicom_series"].size(), 1u);
  EXPECT_EQ(info["dicom_series"][0]["images"], 54);
  EXPECT_EQ(info["dicom_series"][0]["modality"], "CT");
  const CliRun text = Vpm("volume info '" + folder + "?spacing=5'");
  ASSERT_EQ(text.exit_code, 0) << text.output;
  EXPECT_NE(text.output.find("resampled to 5 mm"), std::string::npos) << text.output;
  EXPECT_NE(text.output.find("series      1. "), std::string::npos) << text.output;
  const CliRun bad = Vpm("volume info '" + folder + "?series=2'");
  EXPECT_EQ(bad.exit_code, 2) << bad.output;
  EXPECT_NE(bad.output.find("no series \"2\""), std::string::npos) << bad.output;
}

TEST(VpmCli, BadSourceExitsNonZeroNamingTheFile) {
  const CliRun run = Vpm("volume info /no/such/scan.nii.gz");
  EXPECT_NE(run.exit_code, 0);
  EXPECT_NE(run.output.find("/no/such/scan.nii.gz"), std::string::npos) << run.output;
  EXPECT_NE(Vpm("mesh --volume phantom:nothing").exit_code, 0);
  const CliRun outside = Vpm("mesh --volume 'phantom:abdomen?size=48' --grid 8 8 8 --target 60 "
                          "--refine-at -500 0 0 --backend cpu");
  EXPECT_NE(outside.exit_code, 0);
  EXPECT_NE(outside.output.find("OUT_OF_RANGE"), std::string::npos) << outside.output;
}

TEST(VpmCli, FailedWritesExitNonZeroNamingTheFile) {
  // /dev/full fails every write with ENOSPC, as a full disk does.
  for (const std::string& args : std::vector<std::string>
       {"mesh --volume 'phantom:abdomen?size=32' --json /dev/full",
        "compare-meshes --volume 'phantom:abdomen?size=32' --no-deformation --json /dev/full",
        "volume export 'phantom:abdomen?size=16' " + TempPath("no/such/folder/out.nii.gz")}) {
    const CliRun run = Vpm(args);
    EXPECT_NE(run.exit_code, 0) << args << "\n" << run.output;
    EXPECT_TRUE(run.output.find("/dev/full") != std::string::npos ||
                run.output.find("out.nii.gz") != std::string::npos)
        << args << "\n" << run.output;
  }
}

TEST(VpmCli, MeshWritesJsonWithTheDocumentedFields) {
  const std::string json = TempPath("mesh.json"), vtu = TempPath("mesh.vtu");
  const CliRun run = Vpm("mesh --volume 'phantom:abdomen?size=64' --grid 12 12 12 --target 120 "
                      "--refine-at-landmark left_renal_artery --json " + json + " --vtu " + vtu);
  ASSERT_EQ(run.exit_code, 0) << run.output;
  const auto mesh = ReadJson(json);
  const auto& stats = mesh["stats"];
  for (const char* key : {"evaluate_ms", "decimate_ms", "classify_ms", "refine_ms",
                          "tetrahedralize_ms", "h_mm", "R_mm"}) {
    EXPECT_TRUE(stats.contains(key)) << key;
  }
  int anchors = 0, refined = 0, boundary = 0, steiner = 0;
  for (const auto& v : mesh["vertices"]) {
    anchors += v["kind"] == "anchor";
    refined += v["kind"] == "refined";
    boundary += v["kind"] == "boundary";
    steiner += v["kind"] == "steiner";
    if (v["kind"] != "lattice") {
      EXPECT_EQ(v["lattice_id"], -1);
    }
  }
  EXPECT_EQ(anchors, 8);
  EXPECT_GT(refined, 0);
  EXPECT_EQ(boundary, mesh["stats"]["boundary"]);
  EXPECT_EQ(steiner, mesh["stats"]["steiner"]);
  EXPECT_EQ(mesh["vertices"].size(), 120u + refined + boundary + steiner);
  EXPECT_GT(mesh["tets"].size(), 120u);
  EXPECT_TRUE(std::filesystem::file_size(vtu) > 1000);
}

// The summary names where step 1 ran: `--backend cpu` the CPU reference;
// `auto` on lavapipe (llvmpipe, a CPU device) the native CPU rows, never
// "GPU"; on a GPU the kernels, with the device's name.
TEST(VpmCli, MeshSummarySaysWhereStep1Ran) {
  const std::string flags = " mesh --volume 'phantom:abdomen?size=48' --grid 10 10 10 --target 80";
  const CliRun cpu = Vpm(flags + " --backend cpu");
  ASSERT_EQ(cpu.exit_code, 0) << cpu.output;
  EXPECT_NE(cpu.output.find("(CPU reference)"), std::string::npos) << cpu.output;
  const CliRun automatic = Vpm(flags + " --backend auto");
  ASSERT_EQ(automatic.exit_code, 0) << automatic.output;
  const size_t at = automatic.output.find("\nevaluate ");
  ASSERT_NE(at, std::string::npos) << automatic.output;
  const std::string line =
      automatic.output.substr(at + 1, automatic.output.find('\n', at + 1) - at - 1);
  if (line.find("Vulkan device") == std::string::npos) {
    EXPECT_NE(line.find("(CPU reference)"), std::string::npos) << line;  // no device opened
  } else if (line.find("llvmpipe") != std::string::npos) {
    EXPECT_NE(line.find("(CPU rows, the Vulkan device being a CPU; Vulkan device llvmpipe"),
              std::string::npos) << line;
    EXPECT_EQ(line.find("GPU"), std::string::npos) << line;
  } else {
    EXPECT_NE(line.find("(GPU kernels; Vulkan device "), std::string::npos) << line;
  }
}

// Debian's mricron-data (installed by scripts/install-deps.sh) ships the
// Colin27 T1 template: a real MRI in NIfTI with a RAS sform.
TEST(VpmCli, MeshWorksOnARealMriWithTheMriPreset) {
  const std::string colin = "/usr/share/mricron/templates/ch2.nii.gz";
  ASSERT_TRUE(std::filesystem::exists(colin)) << "install mricron-data (scripts/install-deps.sh)";
  const std::string json = TempPath("colin.json");
  const CliRun run = Vpm("mesh --volume " + colin + " --tf mri-t1 --json " + json);
  ASSERT_EQ(run.exit_code, 0) << run.output;
  const auto mesh = ReadJson(json);
  EXPECT_EQ(mesh["vertices"].size(), 250u + mesh["stats"]["boundary"].get<size_t>() +
                                         mesh["stats"]["steiner"].get<size_t>());
  EXPECT_GT(mesh["tets"].size(), 250u);
}

}  // namespace

namespace {

TEST(VpmCli, OfflineCommandsTakeTheVolumeBudget) {
  // The phantom is float: 48^3 * 4 bytes; one byte less is refused, naming both.
  const CliRun over =
      Vpm("volume info 'phantom:abdomen?size=48' --max-volume-bytes " +
          std::to_string(48 * 48 * 48 * 4 - 1));
  EXPECT_EQ(over.exit_code, 1) << over.output;
  EXPECT_NE(over.output.find("RESOURCE_EXHAUSTED"), std::string::npos) << over.output;
  EXPECT_NE(over.output.find("--max-volume-bytes"), std::string::npos) << over.output;
  EXPECT_NE(over.output.find(std::to_string(48 * 48 * 48 * 4 - 1)), std::string::npos)
      << over.output;
  const CliRun fits = Vpm("volume info 'phantom:abdomen?size=48' --json --max-volume-bytes " +
                          std::to_string(48 * 48 * 48 * 4));
  ASSERT_EQ(fits.exit_code, 0) << fits.output;
  const auto info = nlohmann::json::parse(fits.output.substr(fits.output.find('{')));
  EXPECT_EQ(info["voxel_encoding"], "float32");
  EXPECT_EQ(info["value_bytes"], 48 * 48 * 48 * 4);
}

TEST(VpmCli, ExportOfAnInt16VolumeStaysInt16) {
  // An int16 raw file through export and back: int16, the same values.
  const std::string raw = TempPath("ct16.raw");
  {
    std::ofstream out(raw, std::ios::binary);
    for (int n = 0; n < 4 * 3 * 2; ++n) {
      const int16_t v = static_cast<int16_t>(n * 100 - 1024);
      out.write(reinterpret_cast<const char*>(&v), sizeof(v));
    }
  }
  const std::string nii = TempPath("ct16.nii");
  const CliRun exported = Vpm("volume export 'raw:" + raw +
                              "?dims=4,3,2&type=int16&spacing=1,1,2' " + nii + " --progress");
  ASSERT_EQ(exported.exit_code, 0) << exported.output;
  const CliRun run = Vpm("volume info " + nii + " --json");
  ASSERT_EQ(run.exit_code, 0) << run.output;
  const auto info = nlohmann::json::parse(run.output.substr(run.output.find('{')));
  EXPECT_EQ(info["voxel_encoding"], "int16");
  EXPECT_EQ(info["value_range"], nlohmann::json({-1024.0, 1276.0}));
  EXPECT_EQ(std::filesystem::file_size(nii), 352u + 24 * 2);
}

}  // namespace
