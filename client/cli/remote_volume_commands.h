// `vpm volume load|upload|list|get|delete`: the volume RPCs of a vpm-server
// (LoadVolume, UploadVolume in 1 MiB chunks with SHA-256, ListVolumes,
// GetVolume, DeleteVolume). They join the offline `vpm volume` command.
#pragma once

#include <CLI/CLI.hpp>

#include "client/common/server_connection.h"

namespace vpm::cli {

void AddRemoteVolumeCommands(CLI::App& app, const ServerFlags* flags, int* exit_code);

}  // namespace vpm::cli
