// vpm-view's command line (CLI11): where the server is, what to show, and
// the controls (from key_bindings.h) in --help.
#pragma once

#include <string>

#include <CLI/CLI.hpp>

#include "client/view/interact_connection.h"

namespace vpm::view {

struct ViewFlags {
  ConnectionOptions connection;
  int width = 512;   // frame size asked for at start, pixels (the window adds the status bar)
  int height = 512;
  std::string mode = "dvr";              // "dvr" or "mip"
  std::string preset = "auto";           // DVR preset ("auto": by the image)
  int jpeg_quality = 85;                 // 1..100
  bool overlay = false;                  // proxy-mesh overlay
  // RenderSettings.interactive_quality at start: "auto", "fast", "balanced",
  // "sharp".
  std::string interactive_quality = "auto";
  // The view cut (RenderSettings.view_cut) at start: while no crop box or
  // clip plane is on, cut away what lies in front of the grabbed tissue.
  bool view_cut = true;
  std::string screenshot_dir = ".";      // where S saves vpm-view-*.png
};

// Adds the flags to `app`, with the mouse and key controls as its footer.
void AddViewFlags(CLI::App& app, ViewFlags* flags);
// Defaults filled in after parsing (token from VPM_TOKEN, a volume when
// neither --volume nor --session was given); InvalidArgument for bad values.
Status FinishViewFlags(ViewFlags* flags);

}  // namespace vpm::view
