#include "server/service/server_flags.h"

#include <cstdlib>

#include "server/common/status.h"

namespace vpm::service {
namespace {

// Who may call, and what they may load: the address, tokens, users, the data root.
void AddAccessFlags(CLI::App& app, ServerOptions* o) {
  app.add_option("--listen", o->listen, "HOST:PORT to serve gRPC on (port 0: any free port)")
      ->capture_default_str();
  app.add_option("--token", o->token,
                 "bearer token of the user 'default': every call but health and reflection "
                 "carries a user's token (authorization: Bearer TOKEN); default: env VPM_TOKEN "
                 "(visible in ps: prefer --token-file or --users)");
  app.add_option("--token-file", o->token_file,
                 "read the user 'default''s token from this file (surrounding whitespace "
                 "dropped) instead of --token");
  app.add_option("--users", o->users_file,
                 "users file: one 'NAME TOKEN-SHA256' a line, '#' comments "
                 "(vpm-server --hash-token NAME writes a line); with or without --token");
  app.add_flag("--no-auth", o->no_auth,
               "serve without a token; only on a loopback --listen address");
  app.add_option("--data-root", o->data_root,
                 "folder LoadVolume paths are resolved under (no '..', no symlink escape); "
                 "empty: only phantom: sources and uploads");
}

// The PACS endpoints, their cache and audit log, and vpm as a DICOM node.
void AddPacsFlags(CLI::App& app, ServerOptions* o) {
  app.add_option("--pacs", o->pacs_file,
                 "PACS endpoints file (JSON list: name, dicomweb URL, username + password_file "
                 "or bearer_token_file, ca_file, users; docs/PACS.md): turns on SearchStudies, "
                 "ListSeries and pacs:ENDPOINT/STUDY/SERIES sources");
  app.add_option("--pacs-cache", o->pacs_cache,
                 "folder of retrieved series (mode 0700; default: a private temporary folder "
                 "removed at exit)");
  app.add_option("--pacs-cache-bytes", o->pacs_cache_bytes,
                 "bytes of retrieved series kept on disk; least recently used go first")
      ->capture_default_str()
      ->check(CLI::PositiveNumber);
  app.add_option("--pacs-audit-log", o->pacs_audit_log,
                 "JSON-lines audit log of every PACS action (required with --pacs)");
  app.add_option("--dicom-listen", o->dicom_listen,
                 "AET@HOST:PORT: vpm as a DICOM node (C-STORE, C-ECHO) that PACS and modalities "
                 "send series to and C-MOVE delivers to; needs --pacs (\"receive\" endpoints "
                 "show what arrives); a loopback HOST refuses other peers");
  app.add_option("--dicom-store-bytes", o->dicom_store_bytes,
                 "bytes of received series kept (under --state-dir, else the PACS cache); "
                 "past it instances are refused (out of resources)")
      ->capture_default_str()
      ->check(CLI::PositiveNumber);
  app.add_option("--dicom-max-associations", o->dicom_max_associations,
                 "DICOM associations served at once; more are rejected")
      ->capture_default_str()
      ->check(CLI::Range(1, 64));
  app.add_option("--dicom-max-instance-bytes", o->dicom_max_instance_bytes,
                 "the largest instance received; a larger one ends its association")
      ->capture_default_str()
      ->check(CLI::PositiveNumber);
}

// Metrics and TLS.
void AddTransportFlags(CLI::App& app, ServerOptions* o) {
  app.add_option("--metrics-listen", o->metrics_listen,
                 "HOST:PORT for Prometheus metrics at /metrics (empty: off)");
  app.add_option("--tls-cert", o->tls_cert, "server certificate chain (PEM): turns TLS on");
  app.add_option("--tls-key", o->tls_key, "server private key (PEM)");
  app.add_option("--tls-client-ca", o->tls_client_ca,
                 "CA (PEM) that client certificates must chain to: mutual TLS");
}

// What the server holds and accepts: volumes and uploads.
void AddVolumeLimitFlags(CLI::App& app, ServerOptions* o) {
  app.add_option("--max-volumes", o->max_volumes, "volumes held at once")->capture_default_str();
  app.add_option("--max-volume-bytes", o->max_volume_bytes,
                 "bytes of one volume's values (2 per voxel for integer sources, 4 for "
                 "float; held on the host and again on the GPU), checked before reading; "
                 "the default fits a 512 x 512 x 1,024 int16 CT")
      ->capture_default_str()
      ->check(CLI::PositiveNumber);
  app.add_option("--max-total-volume-bytes", o->max_total_volume_bytes,
                 "host + GPU bytes of all volumes held")->capture_default_str();
  app.add_option("--max-upload-bytes", o->max_upload_bytes, "size of one uploaded file")
      ->capture_default_str();
  app.add_option("--max-upload-memory-bytes", o->max_upload_memory_bytes,
                 "bytes of all uploads in flight (held in memory until complete, counted as "
                 "they arrive); a chunk that would pass it ends its upload")
      ->capture_default_str();
  app.add_option("--max-upload-memory-bytes-per-user", o->max_upload_memory_bytes_per_user,
                 "the same for one user's uploads; an upload declaring more is refused at "
                 "its header (0: no cap)")
      ->capture_default_str();
  app.add_option("--max-upload-spool-bytes", o->max_upload_spool_bytes,
                 "bytes of all uploads bound for the spool, the temporary files they are "
                 "read from (reserved as they arrive, freed when the file is removed; 0: no "
                 "cap)")
      ->capture_default_str();
  app.add_option("--max-upload-spool-bytes-per-user", o->max_upload_spool_bytes_per_user,
                 "the same for one user's uploads; an upload declaring more is refused at its "
                 "header (0: no cap)")
      ->capture_default_str();
  app.add_option("--upload-idle-s", o->upload_idle_s,
                 "an upload that sends no chunk for this long is ended, seconds")
      ->capture_default_str();
  app.add_option("--upload-min-bytes-per-s", o->upload_min_bytes_per_s,
                 "after its first --upload-idle-s, an upload averaging fewer bytes a second "
                 "is ended (a trickle may not hold its memory for ever; 0: no minimum)")
      ->capture_default_str();
  app.add_option("--max-volumes-per-user", o->max_volumes_per_user,
                 "volume slots one user holds at once: their uploads, and the volumes loaded "
                 "from the data root or a phantom that their sessions keep loaded (idle ones "
                 "are shared and evicted; 0: no cap)")
      ->capture_default_str();
}

// What the server holds and accepts: meshes, sessions, frames, connections.
void AddSessionLimitFlags(CLI::App& app, ServerOptions* o) {
  app.add_option("--max-meshes", o->max_meshes, "meshes held at once")->capture_default_str();
  app.add_option("--max-meshes-per-user", o->max_meshes_per_user,
                 "meshes one user's sessions pin at once (unpinned meshes are evicted when "
                 "room is needed; 0: no cap)")
      ->capture_default_str();
  app.add_option("--max-sessions", o->max_sessions, "sessions open at once")
      ->capture_default_str();
  app.add_option("--max-sessions-per-user", o->max_sessions_per_user,
                 "sessions one user owns at once (0: no cap but --max-sessions)")
      ->capture_default_str();
  app.add_option("--max-streams-per-user,--max-streams-per-client", o->max_streams_per_user,
                 "Interact, Watch and UploadVolume streams per user (0: no cap)")
      ->capture_default_str();
  app.add_option("--idle-session-s", o->idle_session_s,
                 "close sessions without calls or viewers for this long, seconds (0: never)")
      ->capture_default_str();
  app.add_option("--idle-watched-session-s", o->idle_watched_session_s,
                 "close sessions that are watched but get no event, camera move or call for "
                 "this long, seconds; their Watch streams end (0: never)")
      ->capture_default_str();
  app.add_option("--max-frame-side", o->max_frame_side, "largest frame width or height, pixels")
      ->capture_default_str();
  app.add_option("--keepalive-time-s", o->keepalive_time_s,
                 "ping an idle connection after this many seconds")->capture_default_str();
  app.add_option("--keepalive-timeout-s", o->keepalive_timeout_s,
                 "drop a connection whose ping is unanswered this long")->capture_default_str();
  app.add_option("--max-message-bytes", o->max_message_bytes,
                 "largest gRPC message received or sent")->capture_default_str();
}

// Worker pools, queues and their fair shares, the still frame and refinement on grab.
void AddWorkFlags(CLI::App& app, ServerOptions* o) {
  app.add_option("--render-threads", o->render_threads, "workers for events and frames")
      ->capture_default_str();
  app.add_option("--request-threads", o->request_threads,
                 "workers for loads, mesh builds and session set-up")->capture_default_str();
  app.add_option("--max-queued-per-user,--max-queued-per-client", o->max_queued_per_user,
                 "unary calls one user (or frames one stream) may have waiting per worker "
                 "pool; past it: RESOURCE_EXHAUSTED with a retry hint (0: no cap)")
      ->capture_default_str();
  app.add_option("--max-queued", o->max_queued,
                 "calls waiting per worker pool, all users (0: no cap)")->capture_default_str();
  app.add_option("--max-running-per-user", o->max_running_per_user,
                 "one user's calls running at once per worker pool (0: the pool's threads "
                 "less one, at least 1: another user's call always finds a free worker)")
      ->capture_default_str();
  app.add_option("--still-delay-ms", o->still_delay_ms,
                 "idle time after a drag before the full-quality still frame")
      ->capture_default_str();
  app.add_option("--refine-min-still-ms", o->refine_min_still_ms,
                 "at rest, sharper rungs before the still only where the still is predicted "
                 "to take this long or more (ms; 0: always)")
      ->capture_default_str();
  app.add_flag("--refine-on-grab,!--no-refine-on-grab", o->refine_on_grab,
               "a grab where the session's mesh is coarse refines it there, built beside the "
               "running mesh and swapped in at the next frame with the manipulation replayed "
               "and recorded in the session's case")
      ->capture_default_str();
}

// Where cases are kept, the drain and shutdown, the GPU.
void AddStateFlags(CLI::App& app, ServerOptions* o) {
  app.add_option("--state-dir", o->state_dir,
                 "keep cases here (DIR/cases.sqlite, created if missing; with --state, only the "
                 "uploads): every session is a case whose manipulations are stored as they are "
                 "acknowledged, reopened after a restart with OpenCase (docs/CASES.md); uploads "
                 "are kept in DIR/blobs for their cases; empty: none are kept");
  app.add_option("--state", o->state_url,
                 "keep cases in PostgreSQL instead (replicas share them): a libpq connection "
                 "string, postgresql://USER@HOST/DB or 'host=... dbname=...'; the password "
                 "comes from PGPASSFILE or ~/.pgpass, never from this flag");
  app.add_option("--drain-s", o->drain_s,
                 "on SIGTERM/SIGINT, report NOT_SERVING to health checks for this long first, "
                 "while calls on existing sessions go on and new volumes, meshes and sessions "
                 "are refused (UNAVAILABLE): a balancer takes the replica out of rotation "
                 "before it stops (longer than its health-check fall time)")
      ->capture_default_str();
  app.add_option("--shutdown-grace-s", o->shutdown_grace_s,
                 "after the drain, streams end and calls get this long before they are cancelled")
      ->capture_default_str();
  app.add_option("--vulkan-device", o->vulkan_device,
                 "GPU by index or name substring (default: env VPM_VULKAN_DEVICE, else automatic)");
}

}  // namespace

void AddServerFlags(CLI::App& app, ServerOptions* o) {
  AddAccessFlags(app, o);
  AddPacsFlags(app, o);
  AddTransportFlags(app, o);
  AddVolumeLimitFlags(app, o);
  AddSessionLimitFlags(app, o);
  AddWorkFlags(app, o);
  AddStateFlags(app, o);
}

void ApplyEnvironment(ServerOptions* o) {
  if (o->token.empty() && o->token_file.empty()) {
    if (const char* token = std::getenv("VPM_TOKEN")) o->token = token;
  }
}

std::vector<std::string> FairShareWarnings(const ServerOptions& o) {
  std::vector<std::string> out;
  auto check = [&](const char* user_flag, int64_t per_user, const char* server_flag,
                   int64_t server) {
    if (per_user <= 0 || server <= 0 || per_user < server) return;
    out.push_back(StrCat(user_flag, " ", per_user, " is not below ", server_flag, " ", server,
                         ": one user at their cap can hold all of it"));
  };
  check("--max-volumes-per-user", o.max_volumes_per_user, "--max-volumes", o.max_volumes);
  check("--max-meshes-per-user", o.max_meshes_per_user, "--max-meshes", o.max_meshes);
  check("--max-sessions-per-user", o.max_sessions_per_user, "--max-sessions", o.max_sessions);
  check("--max-upload-memory-bytes-per-user", o.max_upload_memory_bytes_per_user,
        "--max-upload-memory-bytes", o.max_upload_memory_bytes);
  check("--max-upload-spool-bytes-per-user", o.max_upload_spool_bytes_per_user,
        "--max-upload-spool-bytes", o.max_upload_spool_bytes);
  return out;
}

}  // namespace vpm::service
