// vpm: the command-line client. Offline commands (volume info/export, mesh,
// compare-meshes, render) run the pipeline locally; with --server, mesh and
// render run it on a vpm-server, and the server commands call one RPC each.
#include <CLI/CLI.hpp>

#include "client/cli/compare_meshes_command.h"
#include "client/cli/data_root_commands.h"
#include "client/cli/health_command.h"
#include "client/cli/mesh_command.h"
#include "client/cli/case_commands.h"
#include "client/cli/export_dicom_command.h"
#include "client/cli/pacs_commands.h"
#include "client/cli/play_command.h"
#include "client/cli/remote_mesh_commands.h"
#include "client/cli/remote_volume_commands.h"
#include "client/cli/render_command.h"
#include "client/cli/server_flags.h"
#include "client/cli/session_commands.h"
#include "client/cli/slice_command.h"
#include "client/cli/volume_commands.h"

int main(int argc, char** argv) {
  CLI::App app{"vpm: volume proxy meshes for interactive deformation of CT/MRI volumes"};
  app.require_subcommand(1);
  int exit_code = 0;
  vpm::cli::ServerFlags server_flags;
  vpm::cli::AddServerFlags(app, &server_flags);
  vpm::cli::AddVolumeCommands(app, &exit_code);
  vpm::cli::AddMeshCommand(app, &server_flags, &exit_code);
  vpm::cli::AddCompareMeshesCommand(app, &exit_code);
  vpm::cli::AddRenderCommand(app, &server_flags, &exit_code);
  vpm::cli::AddSliceCommand(app, &server_flags, &exit_code);
  vpm::cli::AddRemoteVolumeCommands(app, &server_flags, &exit_code);
  vpm::cli::AddRemoteMeshCommands(app, &server_flags, &exit_code);
  vpm::cli::AddSessionCommands(app, &server_flags, &exit_code);
  vpm::cli::AddPacsCommands(app, &server_flags, &exit_code);
  vpm::cli::AddDataRootCommands(app, &server_flags, &exit_code);
  vpm::cli::AddExportDicomCommand(app, &server_flags, &exit_code);
  vpm::cli::AddCaseCommands(app, &server_flags, &exit_code);
  vpm::cli::AddPlayCommand(app, &server_flags, &exit_code);
  vpm::cli::AddHealthCommand(app, &server_flags, &exit_code);
  CLI11_PARSE(app, argc, argv);
  return exit_code;
}
