#include "server/service/server_flags.h"

#include <cstdlib>

namespace vpm::service {

void AddServerFlags(CLI::App& app, ServerOptions* o) {
  app.add_option("--listen", o->listen, "HOST:PORT to serve gRPC on (port 0: any free port)")
      ->capture_default_str();
  app.add_option("--token", o->token,
                 "bearer token every call but health and reflection must carry "
                 "(authorization: Bearer TOKEN); default: env VPM_TOKEN");
  app.add_flag("--no-auth", o->no_auth,
               "serve without a token; only on a loopback --listen address");
  app.add_option("--data-root", o->data_root,
                 "folder LoadVolume paths are resolved under (no '..', no symlink escape); "
                 "empty: only phantom: sources and uploads");
  app.add_option("--metrics-listen", o->metrics_listen,
                 "HOST:PORT for Prometheus metrics at /metrics (empty: off)");
  app.add_option("--tls-cert", o->tls_cert, "server certificate chain (PEM): turns TLS on");
  app.add_option("--tls-key", o->tls_key, "server private key (PEM)");
  app.add_option("--tls-client-ca", o->tls_client_ca,
                 "CA (PEM) that client certificates must chain to: mutual TLS");
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
  app.add_option("--max-meshes", o->max_meshes, "meshes held at once")->capture_default_str();
  app.add_option("--max-sessions", o->max_sessions, "sessions open at once")
      ->capture_default_str();
  app.add_option("--max-streams-per-client", o->max_streams_per_client,
                 "Interact + Watch streams per client address (0: no cap)")->capture_default_str();
  app.add_option("--idle-session-s", o->idle_session_s,
                 "close sessions without calls or viewers for this long, seconds (0: never)")
      ->capture_default_str();
  app.add_option("--max-frame-side", o->max_frame_side, "largest frame width or height, pixels")
      ->capture_default_str();
  app.add_option("--keepalive-time-s", o->keepalive_time_s,
                 "ping an idle connection after this many seconds")->capture_default_str();
  app.add_option("--keepalive-timeout-s", o->keepalive_timeout_s,
                 "drop a connection whose ping is unanswered this long")->capture_default_str();
  app.add_option("--max-message-bytes", o->max_message_bytes,
                 "largest gRPC message received or sent")->capture_default_str();
  app.add_option("--render-threads", o->render_threads, "workers for events and frames")
      ->capture_default_str();
  app.add_option("--request-threads", o->request_threads,
                 "workers for loads, mesh builds and session set-up")->capture_default_str();
  app.add_option("--still-delay-ms", o->still_delay_ms,
                 "idle time after a drag before the full-quality still frame")
      ->capture_default_str();
  app.add_option("--shutdown-grace-s", o->shutdown_grace_s,
                 "on SIGTERM/SIGINT, calls get this long before they are cancelled")
      ->capture_default_str();
  app.add_option("--vulkan-device", o->vulkan_device,
                 "GPU by index or name substring (default: env VPM_VULKAN_DEVICE, else automatic)");
}

void ApplyEnvironment(ServerOptions* o) {
  if (o->token.empty()) {
    if (const char* token = std::getenv("VPM_TOKEN")) o->token = token;
  }
}

}  // namespace vpm::service
