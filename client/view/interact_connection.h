// The viewer's link to vpm-server: finds or opens the session, runs one
// Interact stream at a time and, when it ends, says why and reconnects with
// backoff (a restarted server gets the volume loaded and a session opened
// again). Three threads: the connection thread (set-up, then writing the
// queued events), the reader (frames in, JPEG decoded, newest kept) and the
// caller's (Send, TakeFrame, state).
#pragma once

#include <atomic>
#include <functional>
#include <memory>
#include <mutex>
#include <optional>
#include <string>
#include <thread>

#include <glm/glm.hpp>

#include "client/common/server_connection.h"
#include "client/view/outbound_events.h"
#include "client/view/stream_meters.h"
#include "server/raycast/frame_encoder.h"

namespace vpm::view {

struct ConnectionOptions {
  cli::ServerFlags server;
  std::string volume_source;  // loaded when the session is missing or gone
  std::string session_id;     // join this one first
  std::string case_id;        // or open this case (OpenCase)
  bool log_frames = false;    // one stdout line per frame
};

// The newest frame, decoded.
struct ShownFrame {
  DecodedImage image;                // RGBA8, row 0 at the top
  std::vector<DecodedImage> slices;  // Frame.slices, decoded, in order
  v3::Frame info;                    // the frame without its image bytes
  std::optional<double> latency_ms;  // event sent -> this frame, when it shows a new event
  double fps = 0;                    // frames per second received
};

struct ConnectionState {
  bool connected = false;   // a stream is up and has delivered a frame
  std::string message;      // when not connected: what went wrong and what happens next
  uint64_t stream_generation = 0;  // +1 for every new stream (the server forgot any grab)
  std::optional<v3::VolumeInfo> volume;
  std::string session_id;
  std::string mesh_id;
  // The case the session is open on (a server with --state-dir): a server
  // that lost the session (a restart) reopens it, with its manipulations.
  std::string case_id;
};

class InteractConnection {
 public:
  // `wake` is called (from the reader or connection thread) whenever a frame
  // or a state change is ready; it must be thread-safe and cheap.
  InteractConnection(ConnectionOptions options, std::function<void()> wake);
  ~InteractConnection();
  InteractConnection(const InteractConnection&) = delete;
  InteractConnection& operator=(const InteractConnection&) = delete;

  void Start();
  void Stop();

  // Queues an event for the current stream. Settings and camera are also
  // remembered and sent first on every new stream.
  void Send(const v3::ClientEvent& event);
  // Ends the current stream, refines the session's mesh at point_mm, opens
  // a session on the refined mesh and streams from it.
  void RefineAt(const glm::dvec3& point_mm);

  // Undo (redo = false) or redo the session's last action, off the caller's
  // thread; its outcome comes back through TakeNotice. A press while a call
  // runs is refused with a notice.
  void Undo(bool redo);
  // The cases panel's calls, off the caller's thread as Undo: ListCases
  // (the list through TakeCases), UpdateCase (title), DeleteCase.
  void ListCases();
  void RenameCase(const std::string& case_id, const std::string& title);
  void DeleteCase(const std::string& case_id);
  // Ends the stream and streams from `case_id`'s session (OpenCase), with
  // the case's kept view (TakeCaseView).
  void SwitchToCase(const std::string& case_id);
  // The kept view of the case just opened from the panel or --case (GetCase:
  // CaseInfo.view), once: the stream already started with it over the
  // viewer's settings (WithCaseView), the viewer's controls take it now. A
  // reopen after a lost session keeps the viewer's own settings.
  std::optional<v3::RenderSettings> TakeCaseView();
  // What the last call did (or why not), once.
  std::optional<std::string> TakeNotice();
  // The newest ListCases answer (or its error), once.
  std::optional<Result<std::vector<v3::CaseInfo>>> TakeCases();

  // The newest frame since the last call, if any.
  std::optional<ShownFrame> TakeFrame();
  ConnectionState state() const;

 private:
  void Run();
  Status ResolveSession();
  Status Refine(const glm::dvec3& point_mm);
  Status StreamOnce();
  void ReadFrames(grpc::ClientReaderWriter<v3::InteractRequest, v3::Frame>* stream);
  void WriteEvents(grpc::ClientReaderWriter<v3::InteractRequest, v3::Frame>* stream,
                   uint64_t* sequence);
  void SetState(bool connected, std::string message);
  // One unary call with the token and the deadline.
  template <typename Request, typename Response>
  Status Call(grpc::Status (v3::Vpm::Stub::*method)(grpc::ClientContext*, const Request&,
                                                     Response*),
              const Request& request, Response* response) {
    auto context = server_->Context();
    return cli::FromGrpc((server_->stub().*method)(context.get(), request, response));
  }
  void CancelStream();
  // Opens case `case_id` (OpenCase) and joins its session.
  Status OpenCase(const std::string& case_id);
  // Streams from `session` from now on: its volume (GetVolume), mesh and case.
  Status JoinSession(const v3::SessionInfo& session);
  // When a case was asked for (take_case_view_): its kept view over the
  // settings the next stream starts with. A failed GetCase leaves them.
  void TakeCaseViewOf(const std::string& case_id);

  ConnectionOptions options_;
  std::function<void()> wake_;
  std::optional<cli::ServerConnection> server_;
  OutboundEvents events_;

  mutable std::mutex mutex_;  // guards everything below
  ConnectionState state_;
  std::optional<v3::RenderSettings> settings_;
  std::optional<v3::Camera> camera_;
  std::optional<glm::dvec3> refine_at_mm_;
  bool session_opened_here_ = false;
  bool take_case_view_ = false;  // the next OpenCase takes the case's view
  std::optional<v3::RenderSettings> case_view_;  // for TakeCaseView
  std::optional<ShownFrame> newest_;
  LatencyMeter latency_;
  FrameRateMeter frame_rate_;
  grpc::ClientContext* context_ = nullptr;  // of the live stream

  // Runs `call` on a thread of its own (one at a time); its text becomes
  // the notice. False (and a notice) when one still runs.
  bool RunAsync(const char* what, std::function<std::string()> call);

  std::optional<std::string> notice_;
  std::optional<Result<std::vector<v3::CaseInfo>>> cases_;
  std::thread call_thread_;             // the running Undo or case call, if any
  std::atomic<bool> calling_{false};

  std::atomic<bool> stopping_{false};
  std::atomic<bool> stream_ended_{false};
  std::thread thread_;
};

}  // namespace vpm::view
