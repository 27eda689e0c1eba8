// Output files: a whole file written at once (frames, reports, JSON), with every failure
// reported: the file cannot be created, a short write, or an error on close
// (a full disk often shows only there). The message names the path and the
// system's reason: "out/frame.png: cannot write: No space left on device".
#pragma once

#include <filesystem>
#include <string_view>

#include "server/common/status.h"

namespace vpm {

Status WriteFile(const std::filesystem::path& path, std::string_view bytes);

// Creates `dir` and its missing parents for the files above; an error names
// the folder and the reason.
Status MakeDirectories(const std::filesystem::path& dir);

}  // namespace vpm
