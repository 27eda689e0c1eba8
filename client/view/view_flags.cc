#include "client/view/view_flags.h"

#include <cstdlib>

#include "client/view/key_bindings.h"

namespace vpm::view {

inline constexpr char kDefaultVolume[] = "phantom:abdomen";

void AddViewFlags(CLI::App& app, ViewFlags* f) {
  ConnectionOptions& c = f->connection;
  app.add_option("--server", c.server.address, "vpm-server address, HOST:PORT")->required();
  app.add_option("--token", c.server.token, "bearer token (default: env VPM_TOKEN)");
  app.add_option("--tls-ca", c.server.tls_ca, "PEM of the CA that signed the server: use TLS");
  app.add_option("--volume", c.volume_source,
                 "volume to load and open a session on (file under the server's data root, or "
                 "phantom:NAME[?size=N]); also used to reopen after the server lost the session "
                 "(default phantom:abdomen when --session is not given either)");
  app.add_option("--session", c.session_id, "join this existing session");
  app.add_option("--case", c.case_id,
                 "open this case (a server with --state-dir: the open session, or the case "
                 "replayed); the viewer comes back into it after the server restarts");
  app.add_option("--session-key", c.server.session_key,
                 "x-vpm-session of every call, on which a balancer picks the replica (default: "
                 "env VPM_SESSION_KEY, else the key `vpm` uses for this user and host)");
  app.add_option("--size", [f](const CLI::results_t& r) {
                   f->width = std::stoi(r.at(0));
                   f->height = std::stoi(r.at(1));
                   return true;
                 },
                 "frame size W H in pixels (the window follows; resizing it asks for new sizes)")
      ->expected(2)
      ->type_name("W H");
  app.add_option("--mode", f->mode, "dvr or mip")->check(CLI::IsMember({"dvr", "mip"}));
  app.add_option("--preset", f->preset,
                 "DVR preset: auto (ct-soft-tissue on CT, mri-t1 otherwise), ct-soft-tissue, "
                 "ct-bone, ct-vessels, mri-t1, or Slicer's CT-AAA, "
                 "CT-Bone, CT-Muscle, CT-Chest-Contrast-Enhanced, CT-Soft-Tissue, MR-Default");
  app.add_option("--cut", [f](const CLI::results_t& r) {
                   f->view_cut = r.at(0) == "on";
                   return r.at(0) == "on" || r.at(0) == "off";
                 },
                 "start with the view cut on or off (default on: what lies in front of the "
                 "grabbed tissue, or the orbit centre, is cut away while no crop or clip is on)")
      ->type_name("on|off");
  app.add_option("--jpeg-quality", f->jpeg_quality, "1..100")->check(CLI::Range(1, 100));
  app.add_option("--interactive-quality", f->interactive_quality,
                 "frames while moving: auto (the server's device chooses: sharp on a GPU, else "
                 "fast), fast, balanced or sharp (key I cycles; docs/RENDERING.md, "
                 "\"Interactive quality\", gives each one's frame rate and PSNR)")
      ->check(CLI::IsMember({"auto", "fast", "balanced", "sharp"}))
      ->capture_default_str();
  app.add_flag("--overlay", f->overlay, "start with the proxy-mesh overlay on");
  app.add_option("--screenshot-dir", f->screenshot_dir, "folder for screenshots (S key)");
  app.add_flag("--log-frames", c.log_frames,
               "print one line per received frame on stdout (number, size, last sequence, "
               "interactive/still, max_displacement_mm, server total_ms, round-trip rtt_ms)");
  c.server.deadline_s = 120;
  app.add_option("--deadline-s", c.server.deadline_s, "deadline of each unary call, s");
  std::string footer = "\nControls (also on screen with F1 or h):\n";
  for (const std::string& line : HelpLines()) footer += "  " + line + "\n";
  app.footer(footer);
}

Status FinishViewFlags(ViewFlags* f) {
  if (f->connection.server.token.empty()) {
    if (const char* token = std::getenv("VPM_TOKEN")) f->connection.server.token = token;
  }
  if (f->connection.volume_source.empty() && f->connection.session_id.empty() &&
      f->connection.case_id.empty()) {
    f->connection.volume_source = kDefaultVolume;
  }
  if (f->width < 16 || f->height < 16 || f->width > 4096 || f->height > 4096) {
    return absl::InvalidArgumentError(
        StrCat("--size ", f->width, " ", f->height, ": each side must be in 16..4096 pixels"));
  }
  return absl::OkStatus();
}

}  // namespace vpm::view
