// vpm-server killed with SIGKILL at random moments of a scripted session
// (docs/CASES.md, "Never lost"): after each kill the server restarts on the
// same --state-dir, the client reopens its case (OpenCase), and the case
// holds every event the client saw acknowledged (plus at most the one in
// flight) with the deformation and frame of a fresh replay of exactly those
// events. Prints the kill table.
#include <fcntl.h>
#include <signal.h>
#include <sys/wait.h>
#include <unistd.h>

#include <atomic>
#include <chrono>
#include <cmath>
#include <cstdio>
#include <fstream>
#include <random>
#include <set>
#include <sstream>
#include <thread>

#include "server/raycast/frame_encoder.h"
#include "tests/service/service_test_util.h"

namespace vpm::service::testing {
namespace {

namespace fs = std::filesystem;
using Clock = std::chrono::steady_clock;

constexpr char kKillToken[] = "case-kill-test-token";
constexpr char kSmallPhantom[] = "phantom:abdomen?size=40";
constexpr int kKills = 50;

class ServerProcess {
 public:
  ~ServerProcess() { Kill(); }
  // Starts vpm-server on `state_dir`; false (and the log printed) when it
  // does not listen within 60 s.
  bool Start(const fs::path& dir) {
    const fs::path log = dir / "server.log";
    const std::string token_file = (dir / "token").string();
    const std::string state = (dir / "state").string();
    std::ofstream(token_file) << kKillToken;
    std::ofstream(log, std::ios::trunc).close();
    pid_ = fork();
    if (pid_ == 0) {
      const int fd = open(log.c_str(), O_WRONLY | O_APPEND);
      dup2(fd, 1);
      dup2(fd, 2);
      execl(VPM_SERVER_BIN, VPM_SERVER_BIN, "--listen", "127.0.0.1:0", "--token-file",
            token_file.c_str(), "--state-dir", state.c_str(), "--max-sessions", "64",
            "--still-delay-ms", "50",
            // The reference sessions replay the script on the mesh they
            // opened with; a refinement landing at its own moment would
            // make them differ from the case for reasons other than a kill.
            "--no-refine-on-grab", static_cast<char*>(nullptr));
      _exit(127);
    }
    for (int i = 0; i < 1200; ++i) {
      std::ifstream in(log);
      std::string line;
      while (std::getline(in, line)) {
        if (std::sscanf(line.c_str(), "vpm-server listening on port %d", &port_) == 1) {
          channel_ = grpc::CreateChannel("127.0.0.1:" + std::to_string(port_),
                                         grpc::InsecureChannelCredentials());
          stub_ = v3::Vpm::NewStub(channel_);
          return true;
        }
      }
      if (waitpid(pid_, nullptr, WNOHANG) == pid_) break;
      std::this_thread::sleep_for(std::chrono::milliseconds(50));
    }
    std::ifstream in(log);
    std::stringstream text;
    text << in.rdbuf();
    ADD_FAILURE() << "vpm-server did not start:\n" << text.str();
    return false;
  }
  void Kill() {
    if (pid_ <= 0) return;
    kill(pid_, SIGKILL);
    waitpid(pid_, nullptr, 0);
    pid_ = -1;
  }
  pid_t pid() const { return pid_; }
  v3::Vpm::Stub& stub() { return *stub_; }

 private:
  pid_t pid_ = -1;
  int port_ = 0;
  std::shared_ptr<grpc::Channel> channel_;
  std::unique_ptr<v3::Vpm::Stub> stub_;
};

std::unique_ptr<grpc::ClientContext> Ctx(int deadline_s = 60) {
  auto context = std::make_unique<grpc::ClientContext>();
  // Appended, not `std::string("Bearer ") + kKillToken`: GCC 12 warns
  // falsely (-Warray-bounds) on that concatenation once inlined.
  std::string bearer = "Bearer ";
  bearer += kKillToken;
  context->AddMetadata("authorization", bearer);
  context->set_deadline(std::chrono::system_clock::now() + std::chrono::seconds(deadline_s));
  return context;
}

v3::Vec3 Vec(double x, double y, double z) {
  v3::Vec3 v;
  v.set_x(x);
  v.set_y(y);
  v.set_z(z);
  return v;
}

// The scripted session: grabs near the middle of the box, each dragged in
// four steps and released (kept, or let go), now and then a pin or a reset.
std::vector<v3::ClientEvent> Script(const v3::VolumeInfo& volume, int count, uint32_t seed) {
  std::mt19937 rng(seed);
  std::uniform_real_distribution<double> unit(-1.0, 1.0);
  const v3::Vec3& lo = volume.box_lo_lps_mm();
  const v3::Vec3& hi = volume.box_hi_lps_mm();
  auto near_middle = [&] {
    return Vec((lo.x() + hi.x()) / 2 + 0.2 * (hi.x() - lo.x()) * unit(rng),
               (lo.y() + hi.y()) / 2 + 0.2 * (hi.y() - lo.y()) * unit(rng),
               (lo.z() + hi.z()) / 2 + 0.2 * (hi.z() - lo.z()) * unit(rng));
  };
  std::vector<v3::ClientEvent> events;
  while (static_cast<int>(events.size()) < count) {
    const double roll = 0.5 + 0.5 * unit(rng);
    v3::ClientEvent e;
    if (roll < 0.08) {
      *e.mutable_pin()->mutable_point_mm() = near_middle();
      events.push_back(e);
      continue;
    }
    if (roll < 0.2) {
      e.mutable_reset();
      events.push_back(e);
      continue;
    }
    *e.mutable_grab()->mutable_point_mm() = near_middle();
    events.push_back(e);
    const v3::Vec3 d = Vec(4 * unit(rng), 4 * unit(rng), 4 * unit(rng));
    for (int i = 1; i <= 4; ++i) {
      v3::ClientEvent drag;
      *drag.mutable_drag()->mutable_offset_mm() = Vec(d.x() * i / 4, d.y() * i / 4, d.z() * i / 4);
      events.push_back(drag);
    }
    v3::ClientEvent release;
    release.mutable_release()->set_keep(unit(rng) > -0.4);
    events.push_back(release);
  }
  return events;
}

const char* Kind(const v3::ClientEvent& e) {
  switch (e.event_case()) {
    case v3::ClientEvent::kGrab: return "grab";
    case v3::ClientEvent::kDrag: return "drag";
    case v3::ClientEvent::kRelease: return "release";
    case v3::ClientEvent::kPin: return "pin";
    case v3::ClientEvent::kReset: return "reset";
    default: return "other";
  }
}

v3::Frame Still(v3::Vpm::Stub& stub, const std::string& session) {
  v3::RenderRequest request;
  request.set_session_id(session);
  request.mutable_settings()->set_width(96);
  request.mutable_settings()->set_height(96);
  request.mutable_settings()->set_encoding(v3::ENCODING_PNG);
  v3::Frame frame;
  const grpc::Status status = stub.Render(Ctx().get(), request, &frame);
  EXPECT_TRUE(status.ok()) << status.error_message();
  return frame;
}

double MeanDifference(const v3::Frame& a, const v3::Frame& b) {
  auto da = DecodePng({reinterpret_cast<const uint8_t*>(a.image().data()), a.image().size()});
  auto db = DecodePng({reinterpret_cast<const uint8_t*>(b.image().data()), b.image().size()});
  if (!da.ok() || !db.ok() || da->rgba.size() != db->rgba.size()) return 255.0;
  double sum = 0.0;
  for (size_t i = 0; i < da->rgba.size(); ++i) sum += std::abs(int(da->rgba[i]) - int(db->rgba[i]));
  return sum / double(da->rgba.size());
}

// A fresh session on `volume_id` with events [0, n) applied as the live
// session saw them (from the last reset among them on: a reset puts the
// tissue back at rest, whatever came before), a still frame rendered after
// the events counted in `stills` as the client rendered one there: the
// reference state. Its case is deleted afterwards.
v3::Frame Reference(v3::Vpm::Stub& stub, const std::string& volume_id,
                    const std::vector<v3::ClientEvent>& events, int64_t n,
                    const std::set<int64_t>& stills) {
  int64_t from = 0;
  for (int64_t i = 0; i < n; ++i) {
    if (events[i].has_reset()) from = i + 1;
  }
  v3::OpenSessionRequest open;
  open.set_volume_id(volume_id);
  v3::SessionInfo session;
  const grpc::Status opened = stub.OpenSession(Ctx().get(), open, &session);
  EXPECT_TRUE(opened.ok()) << opened.error_message();
  for (int64_t i = from; i < n; ++i) {
    v3::ManipulateRequest request;
    request.set_session_id(session.session_id());
    *request.mutable_event() = events[i];
    v3::ManipulateResponse response;
    const grpc::Status applied = stub.Manipulate(Ctx().get(), request, &response);
    EXPECT_TRUE(applied.ok()) << Kind(events[i]) << " " << i << ": " << applied.error_message();
    if (stills.count(i + 1) != 0 && i + 1 < n) Still(stub, session.session_id());
  }
  const v3::Frame frame = Still(stub, session.session_id());
  v3::DeleteCaseRequest remove;
  remove.set_case_id(session.case_id());
  v3::DeleteCaseResponse removed;
  EXPECT_TRUE(stub.DeleteCase(Ctx().get(), remove, &removed).ok());
  return frame;
}

// Drives `script` from event *acked on while a thread kills the server
// after wait_ms; *acked ends past every event the server acknowledged.
// Returns the kind of the event in flight at the kill ("-": none).
std::string DriveUntilKilled(ServerProcess& server, const std::string& session_id,
                             const std::vector<v3::ClientEvent>& script, int wait_ms,
                             int64_t* acked) {
  std::atomic<bool> killed{false};
  std::thread killer([&] {
    std::this_thread::sleep_for(std::chrono::milliseconds(wait_ms));
    ::kill(server.pid(), SIGKILL);
    killed = true;
  });
  std::string in_flight = "-";
  while (*acked < static_cast<int64_t>(script.size())) {
    v3::ManipulateRequest request;
    request.set_session_id(session_id);
    *request.mutable_event() = script[*acked];
    v3::ManipulateResponse response;
    const grpc::Status status = server.stub().Manipulate(Ctx(10).get(), request, &response);
    if (!status.ok()) {
      EXPECT_TRUE(killed.load()) << status.error_message();
      in_flight = Kind(script[*acked]);
      break;
    }
    ++*acked;
  }
  killer.join();
  return in_flight;
}

// The events the case holds after a restart (-1 when it cannot be read).
int64_t StoredEvents(ServerProcess& server, const std::string& case_id) {
  v3::GetCaseRequest get;
  get.set_case_id(case_id);
  v3::CaseInfo info;
  const grpc::Status status = server.stub().GetCase(Ctx().get(), get, &info);
  EXPECT_TRUE(status.ok()) << status.error_message();
  return status.ok() ? info.events() : -1;
}

// The case reopened into *session; the call's wall ms (-1 on failure).
double ReopenMs(ServerProcess& server, const std::string& case_id, v3::SessionInfo* session) {
  v3::OpenCaseRequest reopen;
  reopen.set_case_id(case_id);
  const auto t0 = Clock::now();
  const grpc::Status status = server.stub().OpenCase(Ctx().get(), reopen, session);
  EXPECT_TRUE(status.ok()) << status.error_message();
  return status.ok() ? std::chrono::duration<double, std::milli>(Clock::now() - t0).count() : -1;
}

TEST(CaseKill, FiftyKillsAtRandomMomentsLoseNoAcknowledgedEvent) {
  const fs::path dir = fs::temp_directory_path() / ("vpm-case-kill-" + std::to_string(getpid()));
  fs::remove_all(dir);
  fs::create_directories(dir);
  ServerProcess server;
  ASSERT_TRUE(server.Start(dir));
  v3::LoadVolumeRequest load;
  load.set_source(kSmallPhantom);
  v3::VolumeInfo volume;
  ASSERT_TRUE(server.stub().LoadVolume(Ctx().get(), load, &volume).ok());
  const std::vector<v3::ClientEvent> script = Script(volume, 4000, 2026);
  v3::OpenSessionRequest open;
  open.set_volume_id(volume.volume_id());
  v3::SessionInfo session;
  ASSERT_TRUE(server.stub().OpenSession(Ctx().get(), open, &session).ok());
  const std::string case_id = session.case_id();
  ASSERT_FALSE(case_id.empty());

  std::mt19937 rng(7);
  std::uniform_int_distribution<int> delay_ms(0, 400);
  int64_t acked = 0;  // events acknowledged so far (a prefix of the script)
  int stored_in_flight = 0;
  std::set<int64_t> stills;  // event counts after which a still frame was rendered
  double worst_mm = 0.0, worst_frame = 0.0, reopen_ms_sum = 0.0, reopen_ms_max = 0.0;
  std::printf("kill  after(ms)  acked  stored  in-flight  reopen(ms)  |dD|(mm)   frame(/255)\n");
  for (int kill = 1; kill <= kKills; ++kill) {
    // Drive the script until the kill lands mid-way, then restart.
    const int wait_ms = delay_ms(rng);
    const std::string in_flight =
        DriveUntilKilled(server, session.session_id(), script, wait_ms, &acked);
    server.Kill();
    ASSERT_TRUE(server.Start(dir));
    // Reopen: the client's own reconnect.
    ASSERT_TRUE(server.stub().LoadVolume(Ctx().get(), load, &volume).ok());
    const int64_t stored = StoredEvents(server, case_id);
    EXPECT_GE(stored, acked) << "kill " << kill << ": an acknowledged event was lost";
    EXPECT_LE(stored, acked + 1) << "kill " << kill;
    if (stored == acked + 1) ++stored_in_flight;
    acked = stored;  // the event in flight was kept: the client goes on after it
    const double reopen_ms = ReopenMs(server, case_id, &session);
    ASSERT_GE(reopen_ms, 0.0);
    reopen_ms_sum += reopen_ms;
    reopen_ms_max = std::max(reopen_ms_max, reopen_ms);
    const v3::Frame reopened = Still(server.stub(), session.session_id());
    const v3::Frame reference = Reference(server.stub(), volume.volume_id(), script, acked, stills);
    stills.insert(acked);
    const double d_mm = std::abs(reopened.max_displacement_mm() - reference.max_displacement_mm());
    const double frame = MeanDifference(reopened, reference);
    worst_mm = std::max(worst_mm, d_mm);
    worst_frame = std::max(worst_frame, frame);
    std::printf("%4d  %9d  %5lld  %6lld  %-9s  %10.0f  %9.2e  %10.4f\n", kill, wait_ms,
                static_cast<long long>(acked), static_cast<long long>(stored), in_flight.c_str(),
                reopen_ms, d_mm, frame);
    EXPECT_LT(d_mm, 1e-3) << "kill " << kill;
    EXPECT_LT(frame, 1.0) << "kill " << kill;
  }
  std::printf("%d kills: every acknowledged event kept; %d in-flight events kept too; largest "
              "|dD| %.2e mm, frame difference %.4f/255; reopen mean %.0f ms, max %.0f ms\n",
              kKills, stored_in_flight, worst_mm, worst_frame, reopen_ms_sum / kKills,
              reopen_ms_max);
  server.Kill();
  fs::remove_all(dir);
}

}  // namespace
}  // namespace vpm::service::testing
