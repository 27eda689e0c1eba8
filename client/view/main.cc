// vpm-view: the workstation viewer. A native window on a vpm-server
// session's Interact stream (docs/VIEW.md).
#include <cstdio>

#include <CLI/CLI.hpp>

#include "client/view/view_flags.h"
#include "client/view/viewer_app.h"

int main(int argc, char** argv) {
  CLI::App app{"vpm-view: a window on a vpm-server session (orbit, zoom, pan, grab and pull)"};
  vpm::view::ViewFlags flags;
  vpm::view::AddViewFlags(app, &flags);
  CLI11_PARSE(app, argc, argv);
  if (vpm::Status s = vpm::view::FinishViewFlags(&flags); !s.ok()) {
    std::fprintf(stderr, "vpm-view: %s\n", std::string(s.message()).c_str());
    return 2;
  }
  vpm::view::ViewerApp viewer(std::move(flags));
  return viewer.Run();
}
