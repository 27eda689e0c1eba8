// Everything vpm-server can be told on its command line (server_flags.h
// documents each one for --help). Limits are caps, 0 means none.
#pragma once

#include <cstdint>
#include <string>

#include "server/volume/volume.h"

namespace vpm::service {

struct ServerOptions {
  std::string listen = "127.0.0.1:50051";  // HOST:PORT; port 0 picks a free one
  std::string token;                       // the user `default`'s bearer token (or env VPM_TOKEN)
  std::string token_file;                  // or read from this file (not on the command line)
  std::string users_file;                  // one `NAME TOKEN-SHA256` a line (users_file.h)
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
  int64_t max_upload_memory_bytes = int64_t{2} << 30;  // all uploads in flight, in memory
  int64_t max_upload_memory_bytes_per_user = int64_t{1} << 30;  // one user's uploads in flight
  // Bytes of uploads bound for the spool (the temporary files they are read
  // from), all users and one user's; reserved as the bytes arrive.
  int64_t max_upload_spool_bytes = int64_t{2} << 30;
  int64_t max_upload_spool_bytes_per_user = int64_t{1} << 30;
  // Volume slots one user holds: their uploads and the shared volumes their
  // sessions keep loaded (0: no cap).
  int64_t max_volumes_per_user = 4;
  int64_t max_meshes_per_user = 16;              // meshes one user's sessions pin (0: no cap)
  double upload_min_bytes_per_s = 16 << 10;      // an upload slower than this on average fails
  double upload_idle_s = 60;                     // an upload with no chunk this long fails
  int64_t max_meshes = 64;
  int64_t max_sessions = 32;
  int64_t max_sessions_per_user = 16;            // sessions one user owns (0: no cap)
  int64_t max_streams_per_user = 8;              // Interact, Watch + upload streams per user
  double idle_session_s = 900;                   // evict sessions idle this long (0: never)
  double idle_watched_session_s = 3600;          // ... watched, but driven by nobody (0: never)
  int max_frame_side = 2048;                     // pixels

  // Transport.
  int keepalive_time_s = 30;                     // server pings an idle connection
  int keepalive_timeout_s = 10;                  // and drops it without an answer
  int max_message_bytes = 16 << 20;              // receive and send

  // Work.
  int render_threads = 2;                        // frame and event workers
  int request_threads = 2;                       // unary workers (load, mesh builds)
  int64_t max_queued_per_user = 64;              // jobs one user (or stream) may have waiting per pool
  int64_t max_running_per_user = 0;              // a user's jobs running at once per pool; 0: threads - 1 (at least 1)
  int64_t max_queued = 1024;                     // jobs waiting per pool, all users
  double still_delay_ms = 150;                   // idle time before a still frame
  // Rungs before a still only where the session's renderer predicts the
  // still's cast at this many ms or more (refine_ladder.h,
  // StillWorthRungs); 0: always.
  double refine_min_still_ms = 100;
  // A grab refines the session's mesh there (docs/SERVICE.md). Off by
  // default: on the phantom the organ lags the pointer more on the refined
  // mesh (an 8 mm drag reaches 5.4 mm at 64^3), which needs a look first.
  bool refine_on_grab = true;
  // Cases (docs/CASES.md): the folder of the case database (cases.sqlite);
  // empty: no cases are kept (sessions live in memory only).
  std::string state_dir;
  // Or a PostgreSQL database shared by replicas (libpq connection string;
  // its password from PGPASSFILE, never here).
  std::string state_url;
  double drain_s = 0;                            // SIGTERM: NOT_SERVING this long first
  double shutdown_grace_s = 5;                   // then streams get this long

  std::string vulkan_device;                     // VPM_VULKAN_DEVICE-style selector

  // PACS (docs/PACS.md): the endpoints file, where retrieved series are
  // kept (empty: a private temporary folder removed at exit) and how many
  // bytes of them, and the audit log every PACS action is recorded in.
  std::string pacs_file;
  std::string pacs_cache;
  int64_t pacs_cache_bytes = int64_t{4} << 30;
  std::string pacs_audit_log;
  // vpm as a DICOM node (docs/PACS.md, "vpm as a DICOM node"): AET@HOST:PORT
  // (empty: off), the received store's budget (bytes), associations at
  // once, and the largest instance taken (bytes).
  std::string dicom_listen;
  int64_t dicom_store_bytes = int64_t{4} << 30;
  int64_t dicom_max_associations = 8;
  int64_t dicom_max_instance_bytes = int64_t{1} << 30;
};

}  // namespace vpm::service
