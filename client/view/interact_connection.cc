#include "client/view/interact_connection.h"

#include <cstdio>
#include <span>
#include <string_view>
#include <utility>

#include "client/view/case_view_settings.h"

namespace vpm::view {
namespace {

std::string Describe(const Status& status) {
  if (absl::IsUnavailable(status)) return StrCat("connection lost: ", status.message());
  return StrCat(absl::StatusCodeToString(status.code()), ": ", status.message());
}

Result<DecodedImage> Decode(const v3::Frame& frame) {
  std::span<const uint8_t> bytes(reinterpret_cast<const uint8_t*>(frame.image().data()),
                                 frame.image().size());
  if (frame.encoding() == v3::ENCODING_PNG) return DecodePng(bytes);
  return DecodeJpeg(bytes);
}

}  // namespace

InteractConnection::InteractConnection(ConnectionOptions options, std::function<void()> wake)
    : options_(std::move(options)), wake_(std::move(wake)) {
  state_.session_id = options_.session_id;
  state_.case_id = options_.case_id;
  take_case_view_ = !options_.case_id.empty() && options_.session_id.empty();
  state_.message = StrCat("connecting to ", options_.server.address, " ...");
}

InteractConnection::~InteractConnection() { Stop(); }

void InteractConnection::Start() { thread_ = std::thread([this] { Run(); }); }

void InteractConnection::Stop() {
  stopping_ = true;
  events_.Close();
  CancelStream();
  if (thread_.joinable()) thread_.join();
  if (call_thread_.joinable()) call_thread_.join();
}

bool InteractConnection::RunAsync(const char* what, std::function<std::string()> call) {
  if (calling_.exchange(true)) {
    std::lock_guard lock(mutex_);
    notice_ = StrCat(what, ": the last call still runs");
    return false;
  }
  if (call_thread_.joinable()) call_thread_.join();
  call_thread_ = std::thread([this, call = std::move(call)] {
    std::string text = server_ ? call() : "not connected";
    {
      std::lock_guard lock(mutex_);
      if (!text.empty()) notice_ = std::move(text);
    }
    calling_ = false;
    wake_();
  });
  return true;
}

void InteractConnection::Undo(bool redo) {
  const std::string session_id = state().session_id;
  RunAsync(redo ? "redo" : "undo", [this, redo, session_id] {
    const char* what = redo ? "redo" : "undo";
    v3::UndoRequest request;
    request.set_session_id(session_id);
    request.set_redo(redo);
    v3::UndoResponse response;
    const Status status = Call(&v3::Vpm::Stub::Undo, request, &response);
    if (!status.ok()) return StrCat(what, ": ", status.message());
    if (!response.changed()) return StrCat("nothing to ", what);
    return StrCat(redo ? "redone" : "undone", ": ", response.events(), " events, ",
                  response.undone(), " undone");
  });
}

void InteractConnection::ListCases() {
  RunAsync("cases", [this] {
    v3::ListCasesResponse response;
    Status status = Call(&v3::Vpm::Stub::ListCases, v3::ListCasesRequest(), &response);
    std::lock_guard lock(mutex_);
    if (status.ok()) {
      cases_ = std::vector<v3::CaseInfo>(response.cases().begin(), response.cases().end());
    } else {
      cases_ = status;
    }
    return std::string();
  });
}

void InteractConnection::RenameCase(const std::string& case_id, const std::string& title) {
  RunAsync("rename", [this, case_id, title] {
    v3::UpdateCaseRequest request;
    request.set_case_id(case_id);
    request.set_title(title);
    v3::CaseInfo info;
    const Status status = Call(&v3::Vpm::Stub::UpdateCase, request, &info);
    return status.ok() ? StrCat("case renamed ", case_id, " ", info.title())
                       : StrCat("rename: ", status.message());
  });
}

void InteractConnection::DeleteCase(const std::string& case_id) {
  RunAsync("delete", [this, case_id] {
    v3::DeleteCaseRequest request;
    request.set_case_id(case_id);
    v3::DeleteCaseResponse response;
    const Status status = Call(&v3::Vpm::Stub::DeleteCase, request, &response);
    return status.ok() ? StrCat("case deleted ", case_id) : StrCat("delete: ", status.message());
  });
}

void InteractConnection::SwitchToCase(const std::string& case_id) {
  {
    std::lock_guard lock(mutex_);
    if (case_id == state_.case_id && !state_.session_id.empty()) return;
    state_.case_id = case_id;
    state_.session_id.clear();  // ResolveSession opens the case
    session_opened_here_ = false;
    take_case_view_ = true;
  }
  CancelStream();
}

std::optional<v3::RenderSettings> InteractConnection::TakeCaseView() {
  std::lock_guard lock(mutex_);
  return std::exchange(case_view_, std::nullopt);
}

std::optional<Result<std::vector<v3::CaseInfo>>> InteractConnection::TakeCases() {
  std::lock_guard lock(mutex_);
  std::optional<Result<std::vector<v3::CaseInfo>>> cases = std::move(cases_);
  cases_.reset();
  return cases;
}

std::optional<std::string> InteractConnection::TakeNotice() {
  std::lock_guard lock(mutex_);
  std::optional<std::string> notice = std::move(notice_);
  notice_.reset();
  return notice;
}

void InteractConnection::Send(const v3::ClientEvent& event) {
  {
    std::lock_guard lock(mutex_);
    if (event.has_settings()) settings_ = event.settings();
    if (event.has_camera()) camera_ = event.camera();
  }
  events_.Push(event);
}

void InteractConnection::RefineAt(const glm::dvec3& point_mm) {
  {
    std::lock_guard lock(mutex_);
    refine_at_mm_ = point_mm;
  }
  CancelStream();
}

std::optional<ShownFrame> InteractConnection::TakeFrame() {
  std::lock_guard lock(mutex_);
  std::optional<ShownFrame> frame = std::move(newest_);
  newest_.reset();
  return frame;
}

ConnectionState InteractConnection::state() const {
  std::lock_guard lock(mutex_);
  return state_;
}

void InteractConnection::SetState(bool connected, std::string message) {
  {
    std::lock_guard lock(mutex_);
    if (state_.connected == connected && state_.message == message) return;
    state_.connected = connected;
    state_.message = std::move(message);
  }
  if (!connected) std::fprintf(stderr, "vpm-view: %s\n", state().message.c_str());
  wake_();
}

void InteractConnection::CancelStream() {
  std::lock_guard lock(mutex_);
  if (context_ != nullptr) context_->TryCancel();
}

void InteractConnection::Run() {
  auto server = cli::ServerConnection::Connect(options_.server);
  if (!server.ok()) return SetState(false, Describe(server.status()));
  server_ = std::move(*server);
  int attempt = 0;
  while (!stopping_) {
    std::optional<glm::dvec3> refine;
    {
      std::lock_guard lock(mutex_);
      refine = refine_at_mm_;
      refine_at_mm_.reset();
    }
    Status status = refine ? Refine(*refine) : ResolveSession();
    const bool opening_failed = !status.ok();
    if (status.ok()) status = StreamOnce();
    if (stopping_) break;
    if (opening_failed && !RetryCanSucceed(status)) {
      // A refused --volume or --session fails the same way every time.
      SetState(false, StrCat(Describe(status), "; not retrying (fix the command line)"));
      std::fprintf(stderr, "vpm-view: %s; not retrying\n", Describe(status).c_str());
      break;
    }
    bool refine_pending;
    {
      std::lock_guard lock(mutex_);
      refine_pending = refine_at_mm_.has_value();
    }
    if (refine_pending) continue;  // the stream was ended to refine: no wait
    // A stream that delivered frames resets the backoff.
    if (state().connected) attempt = 0;
    const double wait_s = ReconnectBackoffS(attempt++);
    SetState(false, StrCat(Describe(status.ok() ? absl::UnavailableError("the server ended the "
                                                                          "stream")
                                                : status),
                           "; reconnecting in ", wait_s, " s (attempt ", attempt, ")"));
    const auto until = SteadyClock::now() + std::chrono::duration<double>(wait_s);
    while (!stopping_ && SteadyClock::now() < until) {
      std::this_thread::sleep_for(std::chrono::milliseconds(20));
    }
  }
}

// Joins the remembered session if the server still has it; otherwise
// reopens its case (a server that restarted keeps cases, not sessions), or
// loads the volume and opens a new one.
Status InteractConnection::ResolveSession() {
  std::string session_id = state().session_id;
  if (!session_id.empty()) {
    v3::ListSessionsResponse sessions;
    RETURN_IF_ERROR(Call(&v3::Vpm::Stub::ListSessions, v3::ListSessionsRequest(), &sessions));
    for (const v3::SessionInfo& s : sessions.sessions()) {
      if (s.session_id() == session_id) return JoinSession(s);
    }
  }
  if (const std::string case_id = state().case_id; !case_id.empty()) return OpenCase(case_id);
  if (!session_id.empty() && options_.volume_source.empty()) {
    return absl::NotFoundError(StrCat("session '", session_id,
                                      "' is gone and no --volume was given to open a new one"));
  }
  if (options_.volume_source.empty()) {
    return absl::InvalidArgumentError("give --session ID, --case ID or --volume SRC");
  }
  SetState(false, StrCat("loading ", options_.volume_source, " ..."));
  v3::LoadVolumeRequest load;
  load.set_source(options_.volume_source);
  v3::VolumeInfo volume;
  RETURN_IF_ERROR(Call(&v3::Vpm::Stub::LoadVolume, load, &volume));
  SetState(false, "opening a session (building the proxy mesh) ...");
  v3::OpenSessionRequest open;
  open.set_volume_id(volume.volume_id());
  v3::SessionInfo session;
  RETURN_IF_ERROR(Call(&v3::Vpm::Stub::OpenSession, open, &session));
  std::fprintf(stderr, "vpm-view: opened session %s on %s (volume %s%s%s)\n",
               session.session_id().c_str(), options_.volume_source.c_str(),
               volume.volume_id().c_str(), session.case_id().empty() ? "" : ", case ",
               session.case_id().c_str());
  // What the reader corrected or chose (a gantry tilt, which series or echo).
  for (const std::string& note : volume.notes()) {
    std::fprintf(stderr, "vpm-view: note: %s\n", note.c_str());
  }
  std::lock_guard lock(mutex_);
  state_.volume = volume;
  state_.session_id = session.session_id();
  state_.mesh_id = session.mesh_id();
  state_.case_id = session.case_id();
  session_opened_here_ = true;
  return absl::OkStatus();
}

Status InteractConnection::OpenCase(const std::string& case_id) {
  SetState(false, StrCat("opening case ", case_id, " (loading, replaying) ..."));
  v3::OpenCaseRequest open;
  open.set_case_id(case_id);
  v3::SessionInfo session;
  RETURN_IF_ERROR(Call(&v3::Vpm::Stub::OpenCase, open, &session));
  RETURN_IF_ERROR(JoinSession(session));
  TakeCaseViewOf(case_id);
  std::fprintf(stderr, "vpm-view: case %s open in session %s\n", case_id.c_str(),
               session.session_id().c_str());
  return absl::OkStatus();
}

void InteractConnection::TakeCaseViewOf(const std::string& case_id) {
  {
    std::lock_guard lock(mutex_);
    if (!std::exchange(take_case_view_, false)) return;
  }
  v3::GetCaseRequest get;
  get.set_case_id(case_id);
  v3::CaseInfo info;
  if (!Call(&v3::Vpm::Stub::GetCase, get, &info).ok() || !info.has_view()) return;
  std::lock_guard lock(mutex_);
  settings_ = WithCaseView(settings_.value_or(v3::RenderSettings()), info.view());
  case_view_ = info.view();
}

Status InteractConnection::JoinSession(const v3::SessionInfo& session) {
  v3::GetVolumeRequest get;
  get.set_volume_id(session.volume_id());
  v3::VolumeInfo volume;
  RETURN_IF_ERROR(Call(&v3::Vpm::Stub::GetVolume, get, &volume));
  std::lock_guard lock(mutex_);
  state_.volume = volume;
  state_.session_id = session.session_id();
  state_.mesh_id = session.mesh_id();
  if (!session.case_id().empty()) state_.case_id = session.case_id();
  return absl::OkStatus();
}

Status InteractConnection::Refine(const glm::dvec3& point_mm) {
  ConnectionState before = state();
  if (!before.volume || before.mesh_id.empty()) return ResolveSession();
  SetState(false, StrCat("refining the mesh at (", point_mm.x, ", ", point_mm.y, ", ",
                         point_mm.z, ") mm ..."));
  v3::RefineMeshRequest refine;
  refine.set_mesh_id(before.mesh_id);
  refine.mutable_point_mm()->set_x(point_mm.x);
  refine.mutable_point_mm()->set_y(point_mm.y);
  refine.mutable_point_mm()->set_z(point_mm.z);
  v3::MeshInfo mesh;
  RETURN_IF_ERROR(Call(&v3::Vpm::Stub::RefineMesh, refine, &mesh));
  v3::OpenSessionRequest open;
  open.set_volume_id(before.volume->volume_id());
  open.set_mesh_id(mesh.mesh_id());
  v3::SessionInfo session;
  RETURN_IF_ERROR(Call(&v3::Vpm::Stub::OpenSession, open, &session));
  bool close_old;
  {
    std::lock_guard lock(mutex_);
    close_old = session_opened_here_;
    state_.session_id = session.session_id();
    state_.mesh_id = session.mesh_id();
    session_opened_here_ = true;
  }
  if (close_old) {
    // The old session was ours alone; a failure only leaves it to expire.
    v3::CloseSessionRequest close;
    close.set_session_id(before.session_id);
    v3::CloseSessionResponse closed;
    (void)Call(&v3::Vpm::Stub::CloseSession, close, &closed);
  }
  std::fprintf(stderr, "vpm-view: refined mesh %s, session %s\n", mesh.mesh_id().c_str(),
               session.session_id().c_str());
  return absl::OkStatus();
}

Status InteractConnection::StreamOnce() {
  auto context = server_->Context(/*streaming=*/true);
  auto stream = server_->stub().Interact(context.get());
  v3::InteractRequest first;
  {
    std::lock_guard lock(mutex_);
    context_ = context.get();
    ++state_.stream_generation;
    latency_.Reset();
    first.set_session_id(state_.session_id);
    if (settings_) *first.mutable_event()->mutable_settings() = *settings_;
  }
  if (stopping_) context->TryCancel();
  events_.Clear();
  events_.Reopen();
  stream_ended_ = false;
  uint64_t sequence = 1;
  first.mutable_event()->set_sequence(sequence);
  {
    std::lock_guard lock(mutex_);
    latency_.Sent(sequence, SteadyClock::now());
    if (camera_) {  // the view this viewer had, restored on the new stream
      v3::ClientEvent camera;
      *camera.mutable_camera() = *camera_;
      events_.Push(camera);
    }
  }
  std::thread reader([&] { ReadFrames(stream.get()); });
  if (stream->Write(first)) WriteEvents(stream.get(), &sequence);
  stream->WritesDone();
  reader.join();
  const Status status = cli::FromStreamEnd(stream->Finish());
  std::lock_guard lock(mutex_);
  context_ = nullptr;
  return status;
}

void InteractConnection::WriteEvents(
    grpc::ClientReaderWriter<v3::InteractRequest, v3::Frame>* stream, uint64_t* sequence) {
  while (!stopping_ && !stream_ended_) {
    std::optional<v3::ClientEvent> event = events_.Pop(std::chrono::milliseconds(100));
    if (!event) continue;
    v3::InteractRequest request;
    *request.mutable_event() = *event;
    request.mutable_event()->set_sequence(++*sequence);
    {
      std::lock_guard lock(mutex_);
      latency_.Sent(*sequence, SteadyClock::now());
    }
    if (!stream->Write(request)) break;  // the stream is broken: Read ends too
  }
  // Stopping: unblock the reader. Otherwise the stream ended by itself and
  // Finish should report why, not a cancellation of ours.
  if (stopping_) CancelStream();
}

void InteractConnection::ReadFrames(
    grpc::ClientReaderWriter<v3::InteractRequest, v3::Frame>* stream) {
  v3::Frame frame;
  while (stream->Read(&frame)) {
    const SteadyClock::time_point now = SteadyClock::now();
    auto image = Decode(frame);
    if (!image.ok()) {
      std::fprintf(stderr, "vpm-view: frame %llu: %s\n",
                   static_cast<unsigned long long>(frame.frame_number()),
                   std::string(image.status().message()).c_str());
      continue;
    }
    ShownFrame shown;
    shown.image = std::move(*image);
    frame.clear_image();
    for (v3::SliceImage& slice : *frame.mutable_slices()) {
      const std::string_view bytes = slice.image();
      const std::span<const uint8_t> data(reinterpret_cast<const uint8_t*>(bytes.data()),
                                          bytes.size());
      auto decoded = slice.encoding() == v3::ENCODING_PNG ? DecodePng(data) : DecodeJpeg(data);
      if (decoded.ok()) shown.slices.push_back(*std::move(decoded));
      slice.clear_image();
    }
    shown.info = frame;
    bool reconnected;
    std::string session_id;
    std::optional<double> latency_ms;
    {
      std::lock_guard lock(mutex_);
      shown.latency_ms = latency_ms = latency_.Received(frame.last_sequence(), now);
      frame_rate_.OnFrame(now);
      shown.fps = frame_rate_.Fps(now);
      reconnected = !state_.connected;
      session_id = state_.session_id;
      state_.connected = true;
      state_.message.clear();
      newest_ = std::move(shown);
    }
    if (reconnected) {
      std::fprintf(stderr, "vpm-view: connected to %s, session %s\n",
                   options_.server.address.c_str(), session_id.c_str());
    }
    if (options_.log_frames) {
      // rtt_ms -1: the frame shows no event that an earlier frame did not.
      std::printf(
          "frame %llu %dx%d seq %llu %s max_displacement_mm %.3f total_ms %.1f rtt_ms %.1f "
          "slices %d\n",
          static_cast<unsigned long long>(frame.frame_number()), frame.width(), frame.height(),
          static_cast<unsigned long long>(frame.last_sequence()),
          frame.interactive() ? "interactive" : "still", frame.max_displacement_mm(),
          frame.timings().total_ms(), latency_ms.value_or(-1.0), frame.slices_size());
      std::fflush(stdout);
    }
    wake_();
  }
  stream_ended_ = true;
  events_.Close();
}

}  // namespace vpm::view
