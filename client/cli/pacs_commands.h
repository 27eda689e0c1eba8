// `vpm pacs search|series|thumbnail`: the PACS RPCs of a vpm-server (SearchStudies,
// ListSeries, GetSeriesThumbnail) on an endpoint of its --pacs file. A series opens with
// `vpm volume load pacs:ENDPOINT/STUDY_UID/SERIES_UID`.
#pragma once

#include <CLI/CLI.hpp>

#include "client/common/server_connection.h"

namespace vpm::cli {

void AddPacsCommands(CLI::App& app, const ServerFlags* flags, int* exit_code);

}  // namespace vpm::cli
