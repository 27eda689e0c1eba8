// Sessions, Render, Manipulate, SetCamera, Interact and Watch: status codes,
// frames, a client that cancels mid-stream, a slow reader, shutdown during a
// stream, the drain before a stop, the per-client stream cap.
#include <thread>

#include "grpc/health/v1/health.grpc.pb.h"
#include "server/raycast/frame_encoder.h"
#include "tests/service/service_test_util.h"

namespace vpm::service::testing {
namespace {

class SessionTest : public PhantomSessionTest {
 protected:
  grpc::Status Manipulate(const v3::ClientEvent& event, v3::ManipulateResponse* response) {
    v3::ManipulateRequest request;
    request.set_session_id(session_.session_id());
    *request.mutable_event() = event;
    auto context = Context();
    return stub_->Manipulate(context.get(), request, response);
  }
  v3::ClientEvent Grab(const v3::Vec3& p, uint64_t sequence) {
    v3::ClientEvent e;
    e.set_sequence(sequence);
    *e.mutable_grab()->mutable_point_mm() = p;
    return e;
  }
  v3::ClientEvent Drag(double dx, uint64_t sequence) {
    v3::ClientEvent e;
    e.set_sequence(sequence);
    *e.mutable_drag()->mutable_offset_mm() = V(dx, 0, 0);
    return e;
  }
  static v3::RenderSettings Small() {
    v3::RenderSettings s;
    s.set_width(96);
    s.set_height(96);
    return s;
  }
  // A Watch of this test's session at 96x96.
  v3::WatchRequest SmallWatch() const {
    v3::WatchRequest request;
    request.set_session_id(session_.session_id());
    *request.mutable_settings() = Small();
    return request;
  }
};

TEST_F(SessionTest, Sessions_OpenListClose) {
  v3::ListSessionsResponse list;
  auto c1 = Context();
  ASSERT_TRUE(stub_->ListSessions(c1.get(), {}, &list).ok());
  ASSERT_EQ(list.sessions_size(), 1);
  EXPECT_EQ(list.sessions(0).volume_id(), volume_.volume_id());

  // A volume in use cannot be deleted.
  v3::DeleteVolumeRequest del;
  del.set_volume_id(volume_.volume_id());
  v3::DeleteVolumeResponse deleted;
  auto c2 = Context();
  EXPECT_EQ(stub_->DeleteVolume(c2.get(), del, &deleted).error_code(),
            grpc::FAILED_PRECONDITION);

  v3::CloseSessionRequest close;
  close.set_session_id(session_.session_id());
  v3::CloseSessionResponse closed;
  auto c3 = Context();
  ASSERT_TRUE(stub_->CloseSession(c3.get(), close, &closed).ok());
  auto c4 = Context();
  EXPECT_EQ(stub_->CloseSession(c4.get(), close, &closed).error_code(), grpc::NOT_FOUND);
}

TEST_F(SessionTest, Sessions_CapAndUnknownIds) {
  OpenSession(volume_.volume_id());
  OpenSession(volume_.volume_id());
  v3::OpenSessionRequest request;
  request.set_volume_id(volume_.volume_id());
  v3::SessionInfo info;
  auto c1 = Context();
  EXPECT_EQ(stub_->OpenSession(c1.get(), request, &info).error_code(), grpc::RESOURCE_EXHAUSTED);
  request.set_volume_id("vol-404");
  auto c2 = Context();
  EXPECT_EQ(stub_->OpenSession(c2.get(), request, &info).error_code(), grpc::NOT_FOUND);
  request.set_volume_id("");
  auto c3 = Context();
  EXPECT_EQ(stub_->OpenSession(c3.get(), request, &info).error_code(), grpc::INVALID_ARGUMENT);
}

TEST_F(SessionTest, Render_ReturnsDecodableStill) {
  v3::RenderRequest request;
  request.set_session_id(session_.session_id());
  *request.mutable_settings() = Small();
  v3::Frame frame;
  auto c1 = Context();
  grpc::Status status = stub_->Render(c1.get(), request, &frame);
  ASSERT_TRUE(status.ok()) << status.error_message();
  EXPECT_EQ(frame.width(), 96);
  EXPECT_FALSE(frame.interactive());
  auto decoded = DecodeJpeg({reinterpret_cast<const uint8_t*>(frame.image().data()),
                             frame.image().size()});
  ASSERT_TRUE(decoded.ok());
  EXPECT_EQ(decoded->height, 96);
  EXPECT_GT(frame.timings().render_ms(), 0.0);

  request.mutable_settings()->set_width(100000);
  auto c2 = Context();
  status = stub_->Render(c2.get(), request, &frame);
  EXPECT_EQ(status.error_code(), grpc::INVALID_ARGUMENT);
  EXPECT_NE(status.error_message().find("settings.width"), std::string::npos);
  request.set_session_id("ses-404");
  auto c3 = Context();
  EXPECT_EQ(stub_->Render(c3.get(), request, &frame).error_code(), grpc::NOT_FOUND);
}

TEST_F(SessionTest, Manipulate_GrabDragReleaseAndTheirErrors) {
  v3::ManipulateResponse response;
  EXPECT_EQ(Manipulate(Drag(3, 1), &response).error_code(), grpc::FAILED_PRECONDITION);
  EXPECT_EQ(Manipulate(Grab(V(-1000, 0, 0), 2), &response).error_code(), grpc::OUT_OF_RANGE);
  EXPECT_EQ(Manipulate(v3::ClientEvent(), &response).error_code(), grpc::INVALID_ARGUMENT);
  ASSERT_TRUE(Manipulate(Grab(Centre(volume_), 3), &response).ok());
  grpc::Status status = Manipulate(Drag(4, 4), &response);
  ASSERT_TRUE(status.ok()) << status.error_message();
  EXPECT_EQ(response.applied_sequence(), 4u);
  EXPECT_GT(response.max_displacement_mm(), 0.0);
  v3::ClientEvent release;
  release.set_sequence(5);
  release.mutable_release();
  ASSERT_TRUE(Manipulate(release, &response).ok());

  v3::SetCameraRequest camera;
  camera.set_session_id(session_.session_id());
  camera.mutable_camera()->set_azimuth_deg(30);
  v3::SetCameraResponse camera_response;
  auto c1 = Context();
  EXPECT_TRUE(stub_->SetCamera(c1.get(), camera, &camera_response).ok());
  camera.mutable_camera()->set_distance_mm(-1);
  auto c2 = Context();
  EXPECT_EQ(stub_->SetCamera(c2.get(), camera, &camera_response).error_code(),
            grpc::INVALID_ARGUMENT);
}

TEST_F(SessionTest, Manipulate_PickBeforeAnyFrameTakesTheOrbitCentrePlane) {
  // No frame yet: no preset to cast with; the default 512x512 view's centre
  // pixel lies on the plane through the orbit centre.
  v3::ClientEvent pick;
  pick.set_sequence(1);
  pick.mutable_grab()->set_pick(true);
  pick.mutable_grab()->set_pixel_x(256);
  pick.mutable_grab()->set_pixel_y(256);
  v3::ManipulateResponse response;
  grpc::Status status = Manipulate(pick, &response);
  ASSERT_TRUE(status.ok()) << status.error_message();
  EXPECT_NEAR(response.grab_point_mm().y(), Centre(volume_).y(), 5.0);
}

TEST_F(SessionTest, Manipulate_PickByPixelGrabsTheSurfaceThePixelShows) {
  // A frame sets the size and preset picks refer to (Manipulate has no stream).
  v3::RenderRequest render;
  render.set_session_id(session_.session_id());
  *render.mutable_settings() = Small();
  v3::Frame frame;
  auto c1 = Context();
  ASSERT_TRUE(stub_->Render(c1.get(), render, &frame).ok());
  v3::ClientEvent pick;
  pick.set_sequence(1);
  pick.mutable_grab()->set_pick(true);
  pick.mutable_grab()->set_pixel_x(48);
  pick.mutable_grab()->set_pixel_y(48);
  v3::ManipulateResponse response;
  grpc::Status status = Manipulate(pick, &response);
  ASSERT_TRUE(status.ok()) << status.error_message();
  ASSERT_TRUE(response.has_grab_point_mm());
  // The default camera looks from the front (anterior, -y) at the volume's
  // centre: the body's surface is in front of the centre, on the camera's
  // side, and the old plane-through-the-centre pick would give the centre.
  const v3::Vec3 centre = Centre(volume_);
  const v3::Vec3& p = response.grab_point_mm();
  EXPECT_LT(p.y(), centre.y() - 20.0) << p.ShortDebugString();
  EXPECT_NEAR(p.x(), centre.x(), 5.0);
  // Frames report the held grab's point.
  auto c2 = Context();
  ASSERT_TRUE(stub_->Render(c2.get(), render, &frame).ok());
  ASSERT_TRUE(frame.has_grab_point_mm());
  EXPECT_DOUBLE_EQ(frame.grab_point_mm().y(), p.y());
  pick.mutable_grab()->set_pixel_x(96);
  EXPECT_EQ(Manipulate(pick, &response).error_code(), grpc::OUT_OF_RANGE);
}

TEST_F(SessionTest, Interact_FramesEchoTheLastEventAndEndWithAStill) {
  auto context = Context();
  auto stream = stub_->Interact(context.get());
  v3::InteractRequest first;
  first.set_session_id(session_.session_id());
  first.mutable_event()->set_sequence(1);
  *first.mutable_event()->mutable_settings() = Small();
  ASSERT_TRUE(stream->Write(first));
  v3::InteractRequest grab;
  *grab.mutable_event() = Grab(Centre(volume_), 2);
  ASSERT_TRUE(stream->Write(grab));
  for (int i = 1; i <= 4; ++i) {
    v3::InteractRequest drag;
    *drag.mutable_event() = Drag(1.5 * i, 2 + i);
    ASSERT_TRUE(stream->Write(drag));
  }
  // Read until a still frame reflects the last event (sequence 6).
  v3::Frame frame;
  bool saw_final_still = false;
  int frames = 0;
  while (stream->Read(&frame)) {
    ++frames;
    EXPECT_EQ(frame.width(), 96);
    if (frame.last_sequence() == 6 && !frame.interactive()) {
      saw_final_still = true;
      EXPECT_GT(frame.max_displacement_mm(), 0.0);
      break;
    }
  }
  EXPECT_TRUE(saw_final_still) << frames << " frames";
  stream->WritesDone();
  grpc::Status status = stream->Finish();
  EXPECT_TRUE(status.ok()) << status.error_message();
}

TEST_F(SessionTest, Interact_BadEventEndsTheStreamWithItsCode) {
  auto context = Context();
  auto stream = stub_->Interact(context.get());
  v3::InteractRequest first;
  first.set_session_id(session_.session_id());
  *first.mutable_event() = Drag(2, 1);  // no grab
  ASSERT_TRUE(stream->Write(first));
  stream->WritesDone();
  v3::Frame frame;
  while (stream->Read(&frame)) {
  }
  EXPECT_EQ(stream->Finish().error_code(), grpc::FAILED_PRECONDITION);

  auto context2 = Context();
  auto stream2 = stub_->Interact(context2.get());
  v3::InteractRequest unknown;
  unknown.set_session_id("ses-404");
  stream2->Write(unknown);
  stream2->WritesDone();
  while (stream2->Read(&frame)) {
  }
  EXPECT_EQ(stream2->Finish().error_code(), grpc::NOT_FOUND);
}

TEST_F(SessionTest, Interact_RejectsMissingToken) {
  auto context = Context("");
  auto stream = stub_->Interact(context.get());
  v3::Frame frame;
  EXPECT_FALSE(stream->Read(&frame));
  EXPECT_EQ(stream->Finish().error_code(), grpc::UNAUTHENTICATED);
}

TEST_F(SessionTest, Interact_ClientCancelMidStreamReleasesEverything) {
  for (int round = 0; round < 3; ++round) {
    auto context = Context();
    auto stream = stub_->Interact(context.get());
    v3::InteractRequest first;
    first.set_session_id(session_.session_id());
    *first.mutable_event()->mutable_settings() = Small();
    ASSERT_TRUE(stream->Write(first));
    v3::Frame frame;
    ASSERT_TRUE(stream->Read(&frame));
    v3::InteractRequest camera;
    camera.mutable_event()->set_sequence(2);
    camera.mutable_event()->mutable_camera()->set_azimuth_deg(45);
    stream->Write(camera);
    context->TryCancel();
    while (stream->Read(&frame)) {
    }
    EXPECT_EQ(stream->Finish().error_code(), grpc::CANCELLED);
  }
  // Every stream the server created is released (OnDone ran).
  for (int i = 0; i < 100 && server_->metrics().streams_closed() <
                                 server_->metrics().streams_opened(); ++i) {
    std::this_thread::sleep_for(std::chrono::milliseconds(50));
  }
  EXPECT_EQ(server_->metrics().streams_opened(), server_->metrics().streams_closed());
  EXPECT_EQ(server_->context().streams->open_streams(), 0);
}

TEST_F(SessionTest, Watch_SlowReaderGetsNewestFrameWithSupersededCounted) {
  auto context = Context();
  v3::WatchRequest request;
  request.set_session_id(session_.session_id());
  // Large lossless frames fill the transport window after one or two, so
  // the server must hold back and drop.
  request.mutable_settings()->set_width(320);
  request.mutable_settings()->set_height(320);
  request.mutable_settings()->set_encoding(v3::ENCODING_PNG);
  // A client whose transport window stays small (no BDP growth): what it
  // does not read stays on the server.
  grpc::ChannelArguments args;
  args.SetInt(GRPC_ARG_HTTP2_BDP_PROBE, 0);
  args.SetInt(GRPC_ARG_HTTP2_STREAM_LOOKAHEAD_BYTES, 16 << 10);
  auto slow_channel = grpc::CreateCustomChannel(
      "127.0.0.1:" + std::to_string(server_->port()), grpc::InsecureChannelCredentials(), args);
  auto slow_stub = v3::Vpm::NewStub(slow_channel);
  auto reader = slow_stub->Watch(context.get(), request);
  v3::Frame frame;
  ASSERT_TRUE(reader->Read(&frame));
  // Camera changes for 4 s while this client does not read.
  int changes = 0;
  const auto until = std::chrono::steady_clock::now() + std::chrono::seconds(4);
  while (std::chrono::steady_clock::now() < until) {
    v3::SetCameraRequest camera;
    camera.set_session_id(session_.session_id());
    camera.mutable_camera()->set_azimuth_deg(++changes * 3.0);
    v3::SetCameraResponse response;
    auto c = Context();
    ASSERT_TRUE(stub_->SetCamera(c.get(), camera, &response).ok());
    std::this_thread::sleep_for(std::chrono::milliseconds(20));
  }
  std::this_thread::sleep_for(std::chrono::milliseconds(500));
  // Far fewer frames arrive than changes were made: the newest won.
  int frames = 0;
  uint64_t superseded = 0;
  std::thread stopper([&] {
    std::this_thread::sleep_for(std::chrono::milliseconds(2000));
    context->TryCancel();
  });
  while (frames < 60 && reader->Read(&frame)) {
    ++frames;
    superseded = frame.superseded_frames();
  }
  stopper.join();
  reader->Finish();
  EXPECT_LT(frames, changes);
  EXPECT_GT(superseded, 0u);
  // What the stream reported is what the server counted; nothing queued.
  EXPECT_EQ(superseded, server_->metrics().superseded());
}

TEST_F(SessionTest, Watch_SeesAnotherClientsManipulation) {
  auto context = Context();
  const v3::WatchRequest request = SmallWatch();
  auto reader = stub_->Watch(context.get(), request);
  v3::Frame frame;
  ASSERT_TRUE(reader->Read(&frame));
  v3::ManipulateResponse response;
  ASSERT_TRUE(Manipulate(Grab(Centre(volume_), 7), &response).ok());
  ASSERT_TRUE(Manipulate(Drag(3, 8), &response).ok());
  bool moved = false;
  while (reader->Read(&frame)) {
    if (frame.last_sequence() == 8 && frame.max_displacement_mm() > 0) {
      moved = true;
      break;
    }
  }
  EXPECT_TRUE(moved);
  context->TryCancel();
  reader->Finish();
}

// A Watch cancelled while the render pool is making its stream: gRPC frees
// its request once the call is done, so the stream's settings must come
// from the reactor's own copy (a reference read freed memory and crashed
// vpm-server). Cancels land at 0-5 ms after the call, across the time the
// pool takes to start the stream; the server then still serves a Watch.
TEST_F(SessionTest, Watch_CancelledWhileItsStreamStartsReadsNoFreedRequest) {
  const v3::WatchRequest request = SmallWatch();
  for (int i = 0; i < 200; ++i) {
    auto context = Context();
    auto reader = stub_->Watch(context.get(), request);
    std::this_thread::sleep_for(std::chrono::microseconds(50 * (i % 100)));
    context->TryCancel();
    reader->Finish();
  }
  auto context = Context();
  auto reader = stub_->Watch(context.get(), request);
  v3::Frame frame;
  EXPECT_TRUE(reader->Read(&frame));
  context->TryCancel();
  reader->Finish();
}

TEST_F(SessionTest, Watch_StreamCapPerClientIsResourceExhausted) {
  std::vector<std::unique_ptr<grpc::ClientContext>> contexts;
  std::vector<std::unique_ptr<grpc::ClientReader<v3::Frame>>> readers;
  const v3::WatchRequest request = SmallWatch();
  for (int i = 0; i < 4; ++i) {
    contexts.push_back(Context());
    readers.push_back(stub_->Watch(contexts.back().get(), request));
    v3::Frame frame;
    ASSERT_TRUE(readers.back()->Read(&frame));
  }
  auto context = Context();
  auto extra = stub_->Watch(context.get(), request);
  v3::Frame frame;
  EXPECT_FALSE(extra->Read(&frame));
  EXPECT_EQ(extra->Finish().error_code(), grpc::RESOURCE_EXHAUSTED);
  for (size_t i = 0; i < readers.size(); ++i) {
    contexts[i]->TryCancel();
    readers[i]->Finish();
  }
}

TEST_F(SessionTest, Shutdown_FinishesOpenStreamsWithUnavailable) {
  auto context = Context();
  const v3::WatchRequest request = SmallWatch();
  auto reader = stub_->Watch(context.get(), request);
  v3::Frame frame;
  ASSERT_TRUE(reader->Read(&frame));
  std::thread stopper([&] { server_->Shutdown(std::chrono::milliseconds(3000)); });
  while (reader->Read(&frame)) {
  }
  EXPECT_EQ(reader->Finish().error_code(), grpc::UNAVAILABLE);
  stopper.join();
  EXPECT_EQ(server_->metrics().streams_opened(), server_->metrics().streams_closed());
}

// BeginDrain (vpm-server --drain-s): health answers NOT_SERVING at once,
// while the session's stream, events and renders go on; calls that would
// create a volume, mesh or session get UNAVAILABLE saying why. The stop
// that follows ends the stream with UNAVAILABLE.
TEST_F(SessionTest, Drain_NotServingWhileTheSessionGoesOn) {
  auto health = grpc::health::v1::Health::NewStub(channel_);
  auto Check = [&] {
    grpc::health::v1::HealthCheckResponse response;
    auto context = Context("");
    const grpc::Status status = health->Check(context.get(), {}, &response);
    EXPECT_TRUE(status.ok()) << status.error_message();
    return response.status();
  };
  ASSERT_EQ(Check(), grpc::health::v1::HealthCheckResponse::SERVING);
  auto watch_context = Context();
  const v3::WatchRequest request = SmallWatch();
  auto reader = stub_->Watch(watch_context.get(), request);
  v3::Frame frame;
  ASSERT_TRUE(reader->Read(&frame));

  server_->BeginDrain();
  EXPECT_EQ(Check(), grpc::health::v1::HealthCheckResponse::NOT_SERVING);
  // The session goes on: a grab and a drag are taken, and the stream shows them.
  v3::ManipulateResponse manipulated;
  ASSERT_TRUE(Manipulate(Grab(Centre(volume_), 1), &manipulated).ok());
  ASSERT_TRUE(Manipulate(Drag(5, 2), &manipulated).ok());
  bool shown = false;
  while (!shown && reader->Read(&frame)) shown = frame.last_sequence() >= 2;
  EXPECT_TRUE(shown) << "no frame of the drag while draining";
  v3::RenderRequest render;
  render.set_session_id(session_.session_id());
  *render.mutable_settings() = Small();
  v3::Frame still;
  auto rc = Context();
  EXPECT_TRUE(stub_->Render(rc.get(), render, &still).ok());
  v3::ListSessionsResponse list;
  auto lc = Context();
  EXPECT_TRUE(stub_->ListSessions(lc.get(), {}, &list).ok());
  // Nothing new is made here any more.
  v3::OpenSessionRequest open;
  open.set_volume_id(volume_.volume_id());
  v3::SessionInfo info;
  auto oc = Context();
  const grpc::Status refused = stub_->OpenSession(oc.get(), open, &info);
  EXPECT_EQ(refused.error_code(), grpc::UNAVAILABLE);
  EXPECT_NE(refused.error_message().find("draining"), std::string::npos) << refused.error_message();
  v3::LoadVolumeRequest load;
  load.set_source("phantom:abdomen?size=32");
  v3::VolumeInfo loaded;
  auto vc = Context();
  EXPECT_EQ(stub_->LoadVolume(vc.get(), load, &loaded).error_code(), grpc::UNAVAILABLE);
  v3::BuildMeshRequest build;
  build.set_volume_id(volume_.volume_id());
  v3::MeshInfo mesh;
  auto bc = Context();
  EXPECT_EQ(stub_->BuildMesh(bc.get(), build, &mesh).error_code(), grpc::UNAVAILABLE);

  std::thread stopper([&] { server_->Shutdown(std::chrono::milliseconds(3000)); });
  while (reader->Read(&frame)) {
  }
  EXPECT_EQ(reader->Finish().error_code(), grpc::UNAVAILABLE);
  stopper.join();
}

// Ids carry the server's random tag: behind a balancer, a session id from
// one replica never names another replica's session.
TEST_F(SessionTest, Ids_CarryTheServersTag) {
  const std::string& tag = server_->id_tag();
  ASSERT_EQ(tag.size(), 8u);
  EXPECT_EQ(tag.find_first_not_of("0123456789abcdef"), std::string::npos) << tag;
  // Session ids: the tag, then 128 random bits (32 hex digits).
  const std::string prefix = "ses-" + tag + "-";
  ASSERT_EQ(session_.session_id().substr(0, prefix.size()), prefix);
  const std::string random = session_.session_id().substr(prefix.size());
  EXPECT_EQ(random.size(), 32u) << session_.session_id();
  EXPECT_EQ(random.find_first_not_of("0123456789abcdef"), std::string::npos) << random;
  // Volume and mesh ids alike: the tag, then 128 random bits.
  for (const std::string& id : {volume_.volume_id(), session_.mesh_id()}) {
    const std::string kind = id.substr(0, id.find('-') + 1);
    EXPECT_TRUE(kind == "vol-" || kind == "mesh-") << id;
    ASSERT_EQ(id.substr(0, kind.size() + tag.size() + 1), kind + tag + "-") << id;
    const std::string bits = id.substr(kind.size() + tag.size() + 1);
    EXPECT_EQ(bits.size(), 32u) << id;
    EXPECT_EQ(bits.find_first_not_of("0123456789abcdef"), std::string::npos) << id;
  }
  auto other = VpmServer::Create(SmallServerOptions(), SharedGpu());
  ASSERT_TRUE(other.ok()) << other.status();
  EXPECT_NE((*other)->id_tag(), tag);
  (*other)->Shutdown(std::chrono::milliseconds(0));
}

TEST_F(SessionTest, CloseSession_EndsItsStreams) {
  auto context = Context();
  const v3::WatchRequest request = SmallWatch();
  auto reader = stub_->Watch(context.get(), request);
  v3::Frame frame;
  ASSERT_TRUE(reader->Read(&frame));
  v3::CloseSessionRequest close;
  close.set_session_id(session_.session_id());
  v3::CloseSessionResponse closed;
  auto c = Context();
  ASSERT_TRUE(stub_->CloseSession(c.get(), close, &closed).ok());
  while (reader->Read(&frame)) {
  }
  // Whoever watched may see it no more.
  EXPECT_EQ(reader->Finish().error_code(), grpc::PERMISSION_DENIED);
}

}  // namespace
}  // namespace vpm::service::testing
