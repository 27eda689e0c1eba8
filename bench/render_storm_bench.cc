// The render storm, timed: an in-process vpm-server on loopback, one
// Interact stream dragging (closed loop: one drag event per frame read,
// 96 x 96 frames of the 48^3 phantom), first alone, then while a second
// connection sends 2,000 Render calls with 1 ms deadlines (one every 2 ms),
// then alone again. Prints the drag's frame rate in each phase, the ratio
// storm / alone (goal >= 80%, issue 15), and how many expired renders ran.
// tests/service/render_storm_test.cc asserts the counts; this measures.
//
// usage: render_storm_bench [--reps N]   (default 3)
#include <algorithm>
#include <atomic>
#include <chrono>
#include <cmath>
#include <cstdio>
#include <cstring>
#include <memory>
#include <string>
#include <thread>
#include <vector>

#include <grpcpp/grpcpp.h>

#include "bench/bench_util.h"
#include "client/common/closed_loop_drag.h"
#include "server/gpu/gpu_context.h"
#include "server/service/vpm_server.h"
#include "vpm/v3/vpm.grpc.pb.h"

namespace {

using Clock = std::chrono::steady_clock;
using Stream = grpc::ClientReaderWriter<vpm::v3::InteractRequest, vpm::v3::Frame>;
constexpr char kToken[] = "bench-token";

std::unique_ptr<grpc::ClientContext> Context(int deadline_ms = 600000) {
  auto context = std::make_unique<grpc::ClientContext>();
  context->AddMetadata("authorization", std::string("Bearer ") + kToken);
  context->set_deadline(std::chrono::system_clock::now() +
                        std::chrono::milliseconds(deadline_ms));
  return context;
}

// Frames a closed-loop drag receives in `seconds` (the stream is grabbing).
int DragFor(Stream* stream, double seconds, uint64_t* sequence) {
  return vpm::cli::DragFor(stream, seconds, sequence).frames;
}

struct Row {
  double alone_fps = 0, storm_fps = 0;
  int ran = 0, expired = 0, refused = 0;
};

Row RunOnce(vpm::service::VpmServer& server, vpm::v3::Vpm::Stub& stub,
            const std::string& session_id, const vpm::v3::Vec3& centre) {
  vpm::v3::RenderSettings small;
  small.set_width(96);
  small.set_height(96);
  auto context = Context();
  auto stream = stub.Interact(context.get());
  vpm::v3::InteractRequest first;
  first.set_session_id(session_id);
  first.mutable_event()->set_sequence(1);
  *first.mutable_event()->mutable_settings() = small;
  *first.mutable_event()->mutable_grab()->mutable_point_mm() = centre;
  vpm::v3::Frame frame;
  if (!stream->Write(first) || !stream->Read(&frame)) {
    std::fprintf(stderr, "render_storm_bench: the Interact stream failed\n");
    std::exit(1);
  }
  uint64_t sequence = 1;
  DragFor(stream.get(), 0.5, &sequence);  // warm up
  Row row;
  constexpr double kAloneS = 2.0;
  int alone = DragFor(stream.get(), kAloneS, &sequence);

  auto storm_channel = grpc::CreateChannel("127.0.0.1:" + std::to_string(server.port()),
                                           grpc::InsecureChannelCredentials());
  auto storm_stub = vpm::v3::Vpm::NewStub(storm_channel);
  constexpr int kCalls = 2000;
  std::atomic<bool> storming{false};
  std::atomic<int> answered{0}, expired{0}, refused{0};
  std::vector<std::unique_ptr<grpc::ClientContext>> contexts(kCalls);
  std::vector<vpm::v3::Frame> frames(kCalls);
  vpm::v3::RenderRequest request;
  request.set_session_id(session_id);
  *request.mutable_settings() = small;
  const double ran_before = server.metrics().requests("Render", "OK");
  std::thread storm([&] {
    storming = true;
    for (int i = 0; i < kCalls; ++i) {
      contexts[i] = Context(1);
      storm_stub->async()->Render(contexts[i].get(), &request, &frames[i],
                                  [&](grpc::Status status) {
                                    expired += status.error_code() == grpc::DEADLINE_EXCEEDED;
                                    refused += status.error_code() == grpc::RESOURCE_EXHAUSTED;
                                    ++answered;
                                  });
      std::this_thread::sleep_for(std::chrono::microseconds(2000));
    }
    storming = false;
  });
  while (!storming) std::this_thread::yield();
  int storm_frames = 0;
  const auto storm_start = Clock::now();
  while (storming) storm_frames += DragFor(stream.get(), 0.25, &sequence);
  const double storm_s = std::chrono::duration<double>(Clock::now() - storm_start).count();
  storm.join();
  while (answered < kCalls) std::this_thread::sleep_for(std::chrono::milliseconds(10));
  alone += DragFor(stream.get(), kAloneS, &sequence);  // alone after, as before

  row.alone_fps = alone / (2 * kAloneS);
  row.storm_fps = storm_frames / storm_s;
  row.ran = int(server.metrics().requests("Render", "OK") - ran_before);
  row.expired = expired;
  row.refused = refused;
  stream->WritesDone();
  while (stream->Read(&frame)) {
  }
  (void)stream->Finish();
  return row;
}

}  // namespace

int main(int argc, char** argv) {
  int reps = 3;
  for (int i = 1; i < argc; ++i) {
    if (!std::strcmp(argv[i], "--reps") && i + 1 < argc) {
      reps = std::max(1, std::atoi(argv[++i]));
    } else {
      std::fprintf(stderr, "usage: render_storm_bench [--reps N]\n");
      return 2;
    }
  }
  auto gpu = vpm::bench::Check(vpm::gpu::GpuContext::Create({}), "Vulkan");
  vpm::service::ServerOptions options;
  options.listen = "127.0.0.1:0";
  options.token = kToken;
  options.still_delay_ms = 100;
  auto server = vpm::bench::Check(vpm::service::VpmServer::Create(options, gpu.get()),
                                  "vpm-server");
  auto channel = grpc::CreateChannel("127.0.0.1:" + std::to_string(server->port()),
                                     grpc::InsecureChannelCredentials());
  auto stub = vpm::v3::Vpm::NewStub(channel);

  vpm::v3::LoadVolumeRequest load;
  load.set_source("phantom:abdomen?size=48");
  vpm::v3::VolumeInfo volume;
  auto c1 = Context();
  vpm::v3::OpenSessionRequest open;
  vpm::v3::SessionInfo session;
  auto c2 = Context();
  grpc::Status status = stub->LoadVolume(c1.get(), load, &volume);
  if (status.ok()) {
    open.set_volume_id(volume.volume_id());
    status = stub->OpenSession(c2.get(), open, &session);
  }
  if (!status.ok()) {
    std::fprintf(stderr, "render_storm_bench: %s\n", status.error_message().c_str());
    return 1;
  }
  vpm::v3::Vec3 centre;
  centre.set_x((volume.dims(0) - 1) * volume.spacing_mm().x() / 2);
  centre.set_y((volume.dims(1) - 1) * volume.spacing_mm().y() / 2);
  centre.set_z((volume.dims(2) - 1) * volume.spacing_mm().z() / 2);

  std::printf("render storm: 2,000 Render calls with 1 ms deadlines during a 96^2 drag\n");
  std::printf("| run | drag alone fps | drag in storm fps | storm/alone | expired renders run | "
              "deadline | refused |\n|---|---|---|---|---|---|---|\n");
  for (int r = 0; r < reps; ++r) {
    const Row row = RunOnce(*server, *stub, session.session_id(), centre);
    std::printf("| %d | %.1f | %.1f | %.0f%% | %d | %d | %d |\n", r + 1, row.alone_fps,
                row.storm_fps, 100 * row.storm_fps / row.alone_fps, row.ran, row.expired,
                row.refused);
    std::fflush(stdout);
  }
  server->Shutdown(std::chrono::milliseconds(2000));
  return 0;
}
