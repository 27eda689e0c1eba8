// `vpm export-dicom --session ID (--to pacs:NAME | --out-dir DIR)`: the
// session's deformed volume as a derived DICOM series and its 3D view as a
// secondary capture, in the source's study (ExportDicom): sent by the server
// to a PACS endpoint, or written here (DIR/derived/*.dcm, DIR/capture/*.dcm).
#pragma once

#include <CLI/CLI.hpp>

#include "client/common/server_connection.h"

namespace vpm::cli {

void AddExportDicomCommand(CLI::App& app, const ServerFlags* flags, int* exit_code);

}  // namespace vpm::cli
