// Everything vpm-server can be told on its command line (server_flags.h
// documents each one for --help). Limits are caps, 0 means none.
#pragma once

#include <cstdint>
#include <string>

#include "server/volume/volume.h"

namespace vpm::service {

struct ServerOptions {
  std::string listen = "127.0.0.1:50051";  // HOST:PORT; port 0 picks a free one
  std::string token;                       // bearer token (or env VPM_TOKEN)
  bool no_auth = false;                    // explicitly off, for local use only
  std::string data_root;                   // LoadVolume paths resolve under it
  std::string metrics_listen;              // HOST:PORT for Prometheus, empty: off

  // TLS: a server certificate and key (PEM files); with a client CA, client
  // certificates are required and verified (mutual TLS).
  std::string tls_cert;
  std::string tls_key;
  std::string tls_client_ca;

  // Limits.
  int64_t max_volumes = 16;
  int64_t max_volume_bytes = kDefaultMaxVolumeBytes;  // one volume's values (host; again on the GPU)
  int64_t max_total_volume_bytes = int64_t{8} << 30;  // host + GPU bytes of every volume held
  int64_t max_upload_bytes = int64_t{1} << 30;   // one uploaded file
  int64_t max_meshes = 64;
  int64_t max_sessions = 32;
  int64_t max_streams_per_client = 8;            // Interact + Watch streams per peer address
  double idle_session_s = 900;                   // evict sessions idle this long (0: never)
  int max_frame_side = 2048;                     // pixels

  // Transport.
  int keepalive_time_s = 30;                     // server pings an idle connection
  int keepalive_timeout_s = 10;                  // and drops it without an answer
  int max_message_bytes = 16 << 20;              // receive and send

  // Work.
  int render_threads = 2;                        // frame and event workers
  int request_threads = 2;                       // unary workers (load, mesh builds)
  double still_delay_ms = 150;                   // idle time before a still frame
  double shutdown_grace_s = 5;                   // SIGTERM: streams get this long

  std::string vulkan_device;                     // VPM_VULKAN_DEVICE-style selector
};

}  // namespace vpm::service
