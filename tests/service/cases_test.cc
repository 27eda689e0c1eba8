// Cases through the API of an in-process server with --state-dir: every
// session is a case, stored as it is made, reopened after a restart with the
// same deformation and frame, undone and redone, shared, deleted.
#include <signal.h>
#include <sys/resource.h>
#include <unistd.h>

#include <cmath>
#include <fstream>
#include <thread>

#include <google/protobuf/util/message_differencer.h>

#include "server/common/sha256.h"
#include "server/raycast/frame_encoder.h"
#include "server/service/users_file.h"
#include "tests/io/archive_test_util.h"
#include "tests/io/dicom_test_util.h"
#include "tests/service/service_test_util.h"

namespace vpm::service::testing {
namespace {

namespace fs = std::filesystem;

constexpr char kAlice[] = "alice-secret-token";
constexpr char kBob[] = "bob-secret-token";

class CasesTest : public ServiceTest {
 protected:
  void SetUp() override {
    dir_ = fs::temp_directory_path() /
           ("vpm-cases-" + std::to_string(::getpid()) + "-" +
            ::testing::UnitTest::GetInstance()->current_test_info()->name());
    fs::remove_all(dir_);
    fs::create_directories(dir_);
    std::ofstream(dir_ / "users.txt") << "alice " << HashToken(kAlice) << "\nbob "
                                      << HashToken(kBob) << "\n";
    StartServer(Options());
  }
  void TearDown() override {
    ServiceTest::TearDown();
    fs::remove_all(dir_);
  }
  ServerOptions Options() const {
    ServerOptions o = SmallServerOptions();
    o.token.clear();
    o.users_file = (dir_ / "users.txt").string();
    o.state_dir = (dir_ / "state").string();
    return o;
  }
  void Restart() {
    server_->Shutdown(std::chrono::milliseconds(2000));
    server_.reset();
    StartServer(Options());
  }

  grpc::Status Manipulate(const std::string& session, const v3::ClientEvent& event,
                          v3::ManipulateResponse* response = nullptr) {
    v3::ManipulateRequest request;
    request.set_session_id(session);
    *request.mutable_event() = event;
    v3::ManipulateResponse ignored;
    return stub_->Manipulate(Context(kAlice).get(), request, response ? response : &ignored);
  }
  static v3::ClientEvent Grab(const v3::Vec3& at) {
    v3::ClientEvent e;
    *e.mutable_grab()->mutable_point_mm() = at;
    return e;
  }
  static v3::ClientEvent Drag(double x, double y, double z) {
    v3::ClientEvent e;
    *e.mutable_drag()->mutable_offset_mm() = V(x, y, z);
    return e;
  }
  static v3::ClientEvent Release(bool keep) {
    v3::ClientEvent e;
    e.mutable_release()->set_keep(keep);
    return e;
  }
  // A still PNG of the session (128 x 128, `settings` else the defaults),
  // and the largest displacement it reports.
  v3::Frame Still(const std::string& session, const v3::RenderSettings& settings = {}) {
    v3::RenderRequest request;
    request.set_session_id(session);
    *request.mutable_settings() = settings;
    request.mutable_settings()->set_width(128);
    request.mutable_settings()->set_height(128);
    request.mutable_settings()->set_encoding(v3::ENCODING_PNG);
    v3::Frame frame;
    const grpc::Status status = stub_->Render(Context(kAlice).get(), request, &frame);
    EXPECT_TRUE(status.ok()) << status.error_message();
    return frame;
  }
  static double MeanDifference(const v3::Frame& a, const v3::Frame& b) {
    return MeanDifference(a.image(), b.image());
  }
  // Of two PNG images, per RGBA byte (255 when they differ in size).
  static double MeanDifference(const std::string& a, const std::string& b) {
    auto da = DecodePng({reinterpret_cast<const uint8_t*>(a.data()), a.size()});
    auto db = DecodePng({reinterpret_cast<const uint8_t*>(b.data()), b.size()});
    EXPECT_TRUE(da.ok() && db.ok());
    if (!da.ok() || !db.ok() || da->rgba.size() != db->rgba.size()) return 255.0;
    double sum = 0.0;
    for (size_t i = 0; i < da->rgba.size(); ++i) sum += std::abs(int(da->rgba[i]) - int(db->rgba[i]));
    return sum / double(da->rgba.size());
  }
  // A session on the phantom with two kept drags and a third grab dragged.
  std::string Plan(const v3::VolumeInfo& volume) {
    const v3::SessionInfo session = OpenSession(volume.volume_id(), kAlice);
    EXPECT_FALSE(session.case_id().empty());
    const v3::Vec3 c = Centre(volume);
    const std::string id = session.session_id();
    EXPECT_TRUE(Manipulate(id, Grab(c)).ok());
    for (int i = 1; i <= 3; ++i) EXPECT_TRUE(Manipulate(id, Drag(0, 0, 2.0 * i)).ok());
    EXPECT_TRUE(Manipulate(id, Release(true)).ok());
    EXPECT_TRUE(Manipulate(id, Grab(V(c.x() + 8, c.y(), c.z()))).ok());
    EXPECT_TRUE(Manipulate(id, Drag(4, 0, 0)).ok());
    return id;
  }
  // OpenCase as Alice: the session, or an empty one (and a failure) when refused.
  v3::SessionInfo OpenCaseAsAlice(const std::string& case_id) {
    v3::OpenCaseRequest open;
    open.set_case_id(case_id);
    v3::SessionInfo session;
    const grpc::Status status = stub_->OpenCase(Context(kAlice).get(), open, &session);
    EXPECT_TRUE(status.ok()) << status.error_message();
    return session;
  }
  v3::CaseInfo GetCase(const std::string& id, const char* token, grpc::Status* status = nullptr) {
    v3::GetCaseRequest request;
    request.set_case_id(id);
    v3::CaseInfo info;
    grpc::Status s = stub_->GetCase(Context(token).get(), request, &info);
    if (status) *status = s;
    return info;
  }

  // A view as a surgeon sets it: the bone preset, a crop box inside the
  // volume, a clip plane through its middle and two slices (world LPS, mm).
  static v3::RenderSettings AView(const v3::VolumeInfo& volume) {
    const v3::Vec3 c = Centre(volume);
    const v3::Vec3 &lo = volume.box_lo_lps_mm(), &hi = volume.box_hi_lps_mm();
    v3::RenderSettings view;
    view.set_preset("ct-bone");
    *view.mutable_crop()->mutable_lo_mm() = V(lo.x() + 2, lo.y() + 3, lo.z() + 4);
    *view.mutable_crop()->mutable_hi_mm() = V(hi.x() - 2, hi.y() - 3, hi.z() - 4);
    v3::ClipPlane* clip = view.add_clip();
    *clip->mutable_normal() = V(1, 0, 0);
    clip->set_offset_mm(c.x() - 5.0);
    v3::SliceSpec* axial = view.add_slices();
    axial->set_orientation(v3::SLICE_ORIENTATION_AXIAL);
    axial->set_at_mm(c.z() + 3.0);
    axial->set_view("axial");
    v3::SliceSpec* coronal = view.add_slices();
    coronal->set_orientation(v3::SLICE_ORIENTATION_CORONAL);
    *coronal->mutable_point_lps_mm() = c;
    coronal->set_view("coronal");
    return view;
  }
  // Sets `view` on an Interact stream of the session (the client's size
  // and encoding with it: 512 x 512, overlay, PNG) and waits for the
  // still that follows it: the case holds the view then.
  void SetViewByInteract(const std::string& session, const v3::RenderSettings& view) {
    auto context = Context(kAlice);
    auto stream = stub_->Interact(context.get());
    v3::InteractRequest first;
    first.set_session_id(session);
    first.mutable_event()->set_sequence(1);
    *first.mutable_event()->mutable_settings() = view;
    v3::RenderSettings* own = first.mutable_event()->mutable_settings();
    own->set_width(512);
    own->set_height(512);
    own->set_overlay(true);
    own->set_encoding(v3::ENCODING_PNG);
    ASSERT_TRUE(stream->Write(first));
    v3::Frame frame;
    bool still = false;
    while (!still && stream->Read(&frame)) {
      still = !frame.interactive() && frame.last_sequence() >= 1;
    }
    EXPECT_TRUE(still);
    stream->WritesDone();
    context->TryCancel();
    stream->Finish().ok();
  }
  // Watches the session with `settings` until a still comes.
  void WatchOneStill(const std::string& session, const v3::RenderSettings& settings) {
    auto context = Context(kAlice);
    v3::WatchRequest request;
    request.set_session_id(session);
    *request.mutable_settings() = settings;
    auto reader = stub_->Watch(context.get(), request);
    v3::Frame frame;
    while (reader->Read(&frame) && frame.interactive()) {
    }
    context->TryCancel();
    reader->Finish().ok();
  }
  std::string GetSessionCase(const std::string& session) {
    v3::GetSessionRequest get;
    get.set_session_id(session);
    v3::SessionInfo info;
    EXPECT_TRUE(stub_->GetSession(Context(kAlice).get(), get, &info).ok());
    return info.case_id();
  }
  // The RGB pixels of the secondary capture ExportDicom streams back.
  std::string CapturePixels(const std::string& session) {
    v3::ExportDicomRequest request;
    request.set_session_id(session);
    auto context = Context(kAlice);
    auto reader = stub_->ExportDicom(context.get(), request);
    v3::ExportDicomPart part;
    std::string capture;
    while (reader->Read(&part)) {
      if (part.file_name().starts_with("capture/")) capture = part.data();
    }
    const grpc::Status status = reader->Finish();
    EXPECT_TRUE(status.ok()) << status.error_message();
    const fs::path file = dir_ / "capture.dcm";
    std::ofstream(file, std::ios::binary) << capture;
    DcmFileFormat dicom;
    const Uint8* pixels = nullptr;
    unsigned long count = 0;
    if (dicom.loadFile(file.c_str()).bad() ||
        dicom.getDataset()->findAndGetUint8Array(DCM_PixelData, pixels, &count).bad()) {
      ADD_FAILURE() << "the capture does not read";
      return "";
    }
    return std::string(reinterpret_cast<const char*>(pixels), count);
  }
  // The capture of a new session on `volume` with nothing set: the defaults.
  std::string CapturePixelsOfNewSession(const v3::VolumeInfo& volume) {
    const v3::SessionInfo fresh = OpenSession(volume.volume_id(), kAlice);
    return CapturePixels(fresh.session_id());
  }

  fs::path dir_;
};

TEST_F(CasesTest, ACaseReopensAfterARestartWithTheSameDeformationAndFrame) {
  const v3::VolumeInfo volume = LoadPhantom(kPhantom, kAlice);
  const std::string session = Plan(volume);
  v3::SetCameraRequest turn;
  turn.set_session_id(session);
  turn.mutable_camera()->set_azimuth_deg(30.0);
  turn.mutable_camera()->set_elevation_deg(15.0);
  v3::SetCameraResponse turned;
  ASSERT_TRUE(stub_->SetCamera(Context(kAlice).get(), turn, &turned).ok());
  const v3::Frame before = Still(session);
  ASSERT_GT(before.max_displacement_mm(), 1.0);
  v3::GetSessionRequest get;
  get.set_session_id(session);
  v3::SessionInfo info;
  ASSERT_TRUE(stub_->GetSession(Context(kAlice).get(), get, &info).ok());
  const std::string case_id = info.case_id();

  Restart();
  v3::ListCasesResponse listed;
  ASSERT_TRUE(stub_->ListCases(Context(kAlice).get(), {}, &listed).ok());
  ASSERT_EQ(listed.cases_size(), 1);
  EXPECT_EQ(listed.cases(0).case_id(), case_id);
  EXPECT_EQ(listed.cases(0).events(), 7);
  EXPECT_EQ(listed.cases(0).source(), kPhantom);
  // The camera is part of the case, and said so.
  ASSERT_TRUE(listed.cases(0).has_camera());
  EXPECT_EQ(listed.cases(0).camera().azimuth_deg(), 30.0);
  EXPECT_EQ(listed.cases(0).camera().elevation_deg(), 15.0);
  EXPECT_TRUE(listed.cases(0).session_id().empty());

  v3::OpenCaseRequest open;
  open.set_case_id(case_id);
  v3::SessionInfo reopened;
  const auto t0 = std::chrono::steady_clock::now();
  const grpc::Status status = stub_->OpenCase(Context(kAlice).get(), open, &reopened);
  const double open_ms =
      std::chrono::duration<double, std::milli>(std::chrono::steady_clock::now() - t0).count();
  ASSERT_TRUE(status.ok()) << status.error_message();
  EXPECT_EQ(reopened.case_id(), case_id);
  const v3::Frame after = Still(reopened.session_id());
  const double frame_difference = MeanDifference(before, after);
  std::printf("reopen: %.0f ms; largest displacement %.6f -> %.6f mm; frame mean difference "
              "%.4f / 255\n", open_ms, before.max_displacement_mm(), after.max_displacement_mm(),
              frame_difference);
  EXPECT_NEAR(after.max_displacement_mm(), before.max_displacement_mm(), 1e-3);
  EXPECT_LT(frame_difference, 1.0);
  // Opening it again gives the same session, not a second one.
  v3::SessionInfo again;
  ASSERT_TRUE(stub_->OpenCase(Context(kAlice).get(), open, &again).ok());
  EXPECT_EQ(again.session_id(), reopened.session_id());
  EXPECT_EQ(GetCase(case_id, kAlice).session_id(), reopened.session_id());
}

TEST_F(CasesTest, ACaseOfAnUploadReopensAfterARestartFromTheKeptFile) {
  const std::vector<uint8_t> bytes = NiftiBytes();
  v3::VolumeInfo volume;
  ASSERT_TRUE(Upload(bytes, int64_t(bytes.size()), Sha256::HexOf(bytes), 64 << 10, &volume, true,
                     kAlice)
                  .ok());
  const std::string session = Plan(volume);
  const double planned = Still(session).max_displacement_mm();
  v3::GetSessionRequest get;
  get.set_session_id(session);
  v3::SessionInfo info;
  ASSERT_TRUE(stub_->GetSession(Context(kAlice).get(), get, &info).ok());
  const v3::CaseInfo kept = GetCase(info.case_id(), kAlice);
  EXPECT_EQ(kept.source(), "upload:" + Sha256::HexOf(bytes) + "/case.nii");
  // Content-addressed: the file is there once, under its hash.
  EXPECT_TRUE(fs::is_regular_file(dir_ / "state" / "blobs" / Sha256::HexOf(bytes) / "case.nii"));

  Restart();
  const v3::SessionInfo reopened = OpenCaseAsAlice(info.case_id());
  ASSERT_FALSE(reopened.session_id().empty());
  EXPECT_NEAR(Still(reopened.session_id()).max_displacement_mm(), planned, 1e-3);
  // The volume it reads is Alice's own, as her upload was.
  v3::GetVolumeRequest volume_request;
  volume_request.set_volume_id(reopened.volume_id());
  v3::VolumeInfo read_again;
  EXPECT_EQ(stub_->GetVolume(Context(kBob).get(), volume_request, &read_again).error_code(),
            grpc::NOT_FOUND);
  // Deleting the case deletes the kept file: it was the case's data.
  v3::DeleteCaseRequest remove;
  remove.set_case_id(info.case_id());
  v3::DeleteCaseResponse removed;
  ASSERT_TRUE(stub_->DeleteCase(Context(kAlice).get(), remove, &removed).ok());
  EXPECT_FALSE(fs::exists(dir_ / "state" / "blobs" / Sha256::HexOf(bytes)));
}

// A DICOM series uploaded as a zip (a folder dropped in the browser) reads
// as a series of its user's, and its case reopens from the kept archive.
TEST_F(CasesTest, ADicomSeriesUploadedAsAZipReadsAsASeriesAndItsCaseReopens) {
  std::vector<vpm::testing::ArchiveEntry> slices;
  const fs::path folder = dir_ / "series";
  fs::create_directories(folder);
  for (int k = 0; k < 24; ++k) {
    vpm::testing::DicomSliceSpec s;
    s.rows = 20;
    s.columns = 24;
    s.pixel_spacing_mm = {2.0, 2.0};
    s.position_mm = {0.0, 0.0, 2.0 * k};
    s.stored.resize(20 * 24);
    for (int n = 0; n < 20 * 24; ++n) {
      const int i = n % 24, j = n / 24;
      const bool organ = std::abs(i - 12) < 6 && std::abs(j - 10) < 5 && std::abs(k - 12) < 6;
      s.stored[n] = organ ? 1100 : (i < 2 ? 2500 : 1000);  // HU +76, bone at the edge, 0
    }
    const fs::path file = folder / ("IM" + std::to_string(k));
    ASSERT_TRUE(vpm::testing::WriteDicomSlice(file, s));
    slices.push_back({"patient/series/IM" + std::to_string(k), vpm::testing::ReadAll(file)});
  }
  vpm::testing::WriteArchive(dir_ / "series.zip", slices, true);
  const std::string zipped = vpm::testing::ReadAll(dir_ / "series.zip");
  const std::vector<uint8_t> bytes(zipped.begin(), zipped.end());
  v3::VolumeInfo volume;
  const grpc::Status uploaded = Upload(bytes, int64_t(bytes.size()), Sha256::HexOf(bytes),
                                       64 << 10, &volume, true, kAlice, "series.zip");
  ASSERT_TRUE(uploaded.ok()) << uploaded.error_message();
  EXPECT_EQ(volume.dims(0), 24);
  EXPECT_EQ(volume.dims(1), 20);
  EXPECT_EQ(volume.dims(2), 24);
  EXPECT_EQ(volume.owner(), "alice");
  const std::string session = Plan(volume);
  // On this small grid a still's bounded settle takes a few frames to come
  // to rest: stills until it has (each settle is stored, so the reopened
  // case takes the same path).
  double planned = Still(session).max_displacement_mm();
  for (int i = 0; i < 20; ++i) {
    const double next = Still(session).max_displacement_mm();
    if (std::abs(next - planned) < 1e-5) break;
    planned = next;
  }
  ASSERT_GT(planned, 0.5);
  v3::GetSessionRequest get;
  get.set_session_id(session);
  v3::SessionInfo info;
  ASSERT_TRUE(stub_->GetSession(Context(kAlice).get(), get, &info).ok());
  EXPECT_EQ(GetCase(info.case_id(), kAlice).source(),
            "upload:" + Sha256::HexOf(bytes) + "/series.zip");

  Restart();
  const v3::SessionInfo reopened = OpenCaseAsAlice(info.case_id());
  ASSERT_FALSE(reopened.session_id().empty());
  EXPECT_NEAR(Still(reopened.session_id()).max_displacement_mm(), planned, 1e-3);

  // A zip without a series is the user's malformed upload, said plainly.
  vpm::testing::WriteArchive(dir_ / "notes.zip", {{"notes.txt", "no images"}}, true);
  const std::string notes = vpm::testing::ReadAll(dir_ / "notes.zip");
  const std::vector<uint8_t> note_bytes(notes.begin(), notes.end());
  v3::VolumeInfo refused;
  const grpc::Status bad = Upload(note_bytes, int64_t(note_bytes.size()),
                                  Sha256::HexOf(note_bytes), 64 << 10, &refused, true, kAlice,
                                  "notes.zip");
  EXPECT_EQ(bad.error_code(), grpc::INVALID_ARGUMENT) << bad.error_message();
  EXPECT_EQ(bad.error_message().find("/tmp"), std::string::npos) << bad.error_message();
}

TEST_F(CasesTest, UndoTakesBackTheLastActionAndRedoBringsItBack) {
  const v3::VolumeInfo volume = LoadPhantom(kPhantom, kAlice);
  const std::string session = Plan(volume);
  const double planned = Still(session).max_displacement_mm();
  v3::UndoRequest undo;
  undo.set_session_id(session);
  v3::UndoResponse response;
  ASSERT_TRUE(stub_->Undo(Context(kAlice).get(), undo, &response).ok());
  EXPECT_TRUE(response.changed());
  EXPECT_EQ(response.events(), 5);  // the first grab, three drags, its kept release
  EXPECT_EQ(response.undone(), 2);
  const double first_only = Still(session).max_displacement_mm();
  EXPECT_GT(std::abs(first_only - planned), 1e-3);
  ASSERT_TRUE(stub_->Undo(Context(kAlice).get(), undo, &response).ok());
  EXPECT_EQ(response.events(), 0);
  EXPECT_NEAR(Still(session).max_displacement_mm(), 0.0, 1e-9);
  ASSERT_TRUE(stub_->Undo(Context(kAlice).get(), undo, &response).ok());
  EXPECT_FALSE(response.changed());

  undo.set_redo(true);
  ASSERT_TRUE(stub_->Undo(Context(kAlice).get(), undo, &response).ok());
  ASSERT_TRUE(stub_->Undo(Context(kAlice).get(), undo, &response).ok());
  EXPECT_EQ(response.events(), 7);
  EXPECT_NEAR(Still(session).max_displacement_mm(), planned, 1e-3);
  // A drag after an undo drops what was undone.
  undo.set_redo(false);
  ASSERT_TRUE(stub_->Undo(Context(kAlice).get(), undo, &response).ok());
  ASSERT_TRUE(Manipulate(session, Grab(Centre(volume))).ok());
  undo.set_redo(true);
  ASSERT_TRUE(stub_->Undo(Context(kAlice).get(), undo, &response).ok());
  EXPECT_FALSE(response.changed());
  EXPECT_EQ(response.events(), 6);
}

TEST_F(CasesTest, OthersSeeNoCaseUntilSharedAndADeletedCaseIsGone) {
  const v3::VolumeInfo volume = LoadPhantom(kPhantom, kAlice);
  const std::string session = Plan(volume);
  v3::GetSessionRequest get;
  get.set_session_id(session);
  v3::SessionInfo info;
  ASSERT_TRUE(stub_->GetSession(Context(kAlice).get(), get, &info).ok());
  const std::string id = info.case_id();

  grpc::Status theirs, missing;
  GetCase(id, kBob, &theirs);
  GetCase("case-00000000000000000000000000000000", kBob, &missing);
  EXPECT_EQ(theirs.error_code(), grpc::NOT_FOUND);
  EXPECT_EQ(missing.error_code(), grpc::NOT_FOUND);
  EXPECT_EQ(theirs.error_message().size(), missing.error_message().size());
  v3::ListCasesResponse bobs;
  ASSERT_TRUE(stub_->ListCases(Context(kBob).get(), {}, &bobs).ok());
  EXPECT_EQ(bobs.cases_size(), 0);

  v3::ShareCaseRequest share;
  share.set_case_id(id);
  share.set_user("bob");
  v3::CaseInfo shared;
  ASSERT_TRUE(stub_->ShareCase(Context(kAlice).get(), share, &shared).ok());
  EXPECT_EQ(shared.shared_with_size(), 1);
  grpc::Status readable;
  const v3::CaseInfo seen = GetCase(id, kBob, &readable);
  ASSERT_TRUE(readable.ok()) << readable.error_message();
  EXPECT_EQ(seen.owner(), "alice");
  EXPECT_EQ(seen.shared_with_size(), 0);  // shown to the owner only
  v3::OpenCaseRequest open;
  open.set_case_id(id);
  v3::SessionInfo bobs_session;
  EXPECT_EQ(stub_->OpenCase(Context(kBob).get(), open, &bobs_session).error_code(),
            grpc::NOT_FOUND);
  // Bob may watch the open session of a case shared with him.
  ASSERT_TRUE(stub_->GetSession(Context(kBob).get(), get, &info).ok());

  v3::UpdateCaseRequest rename;
  rename.set_case_id(id);
  rename.set_title("left kidney, medial");
  v3::CaseInfo renamed;
  ASSERT_TRUE(stub_->UpdateCase(Context(kAlice).get(), rename, &renamed).ok());
  EXPECT_EQ(renamed.title(), "left kidney, medial");
  EXPECT_EQ(stub_->UpdateCase(Context(kBob).get(), rename, &renamed).error_code(),
            grpc::NOT_FOUND);

  v3::DeleteCaseRequest remove;
  remove.set_case_id(id);
  v3::DeleteCaseResponse removed;
  EXPECT_EQ(stub_->DeleteCase(Context(kBob).get(), remove, &removed).error_code(),
            grpc::NOT_FOUND);
  ASSERT_TRUE(stub_->DeleteCase(Context(kAlice).get(), remove, &removed).ok());
  grpc::Status gone;
  GetCase(id, kAlice, &gone);
  EXPECT_EQ(gone.error_code(), grpc::NOT_FOUND);
  // Its session closed with it.
  EXPECT_EQ(stub_->GetSession(Context(kAlice).get(), get, &info).error_code(), grpc::NOT_FOUND);
}

TEST_F(CasesTest, AnExportedCaseImportsAsANewCaseWithTheSameDeformation) {
  const v3::VolumeInfo volume = LoadPhantom(kPhantom, kAlice);
  const std::string session = Plan(volume);
  const double planned = Still(session).max_displacement_mm();
  v3::GetSessionRequest get;
  get.set_session_id(session);
  v3::SessionInfo info;
  ASSERT_TRUE(stub_->GetSession(Context(kAlice).get(), get, &info).ok());
  v3::ExportCaseRequest request;
  request.set_case_id(info.case_id());
  v3::CaseArchive archive;
  ASSERT_TRUE(stub_->ExportCase(Context(kAlice).get(), request, &archive).ok());
  EXPECT_EQ(archive.format_version(), 1);
  EXPECT_EQ(archive.source(), kPhantom);
  ASSERT_EQ(archive.events_size(), 7);
  EXPECT_EQ(archive.events(0).kind(), v3::CASE_EVENT_GRAB);
  // The grab point is world LPS: the middle of the box, as the plan sent it.
  const v3::Vec3 c = Centre(volume);
  EXPECT_NEAR(archive.events(0).point_mm().x(), c.x(), 1e-9);
  EXPECT_NEAR(archive.events(0).point_mm().z(), c.z(), 1e-9);
  EXPECT_EQ(stub_->ExportCase(Context(kBob).get(), request, &archive).error_code(), grpc::NOT_FOUND);

  // Bob imports Alice's file (she sent it to him): a case of his own.
  v3::ImportCaseRequest import;
  *import.mutable_archive() = archive;
  v3::CaseInfo imported;
  const grpc::Status status = stub_->ImportCase(Context(kBob).get(), import, &imported);
  ASSERT_TRUE(status.ok()) << status.error_message();
  EXPECT_NE(imported.case_id(), info.case_id());
  EXPECT_EQ(imported.owner(), "bob");
  EXPECT_EQ(imported.events(), 7);
  v3::OpenCaseRequest open;
  open.set_case_id(imported.case_id());
  v3::SessionInfo bobs;
  ASSERT_TRUE(stub_->OpenCase(Context(kBob).get(), open, &bobs).ok());
  v3::RenderRequest render;
  render.set_session_id(bobs.session_id());
  render.mutable_settings()->set_width(64);
  render.mutable_settings()->set_height(64);
  v3::Frame frame;
  ASSERT_TRUE(stub_->Render(Context(kBob).get(), render, &frame).ok());
  EXPECT_NEAR(frame.max_displacement_mm(), planned, 1e-3);

  // A damaged archive is refused whole, naming the fault.
  v3::ImportCaseRequest bad = import;
  bad.mutable_archive()->mutable_events(3)->mutable_vector()->set_x(std::nan(""));
  EXPECT_EQ(stub_->ImportCase(Context(kBob).get(), bad, &imported).error_code(),
            grpc::INVALID_ARGUMENT);
  bad = import;
  bad.mutable_archive()->set_format_version(9);
  grpc::Status refused = stub_->ImportCase(Context(kBob).get(), bad, &imported);
  EXPECT_EQ(refused.error_code(), grpc::INVALID_ARGUMENT);
  EXPECT_NE(refused.error_message().find("format_version"), std::string::npos);
  v3::ListCasesResponse bobs_cases;
  ASSERT_TRUE(stub_->ListCases(Context(kBob).get(), {}, &bobs_cases).ok());
  EXPECT_EQ(bobs_cases.cases_size(), 1);
}

// The view a client set on its stream (a preset, a crop box, a clip plane,
// two slices) is part of the case: written with the stream's still, kept
// across a restart, returned by CaseInfo (without the client's frame size
// and encoding), and the reopened session starts with it: its export's
// capture, a frame no client asked for, and a still with CaseInfo.view are
// those of before. A Watch stream's settings are never kept.
TEST_F(CasesTest, ACaseKeepsItsViewAndTheReopenedSessionShowsIt) {
  const v3::VolumeInfo volume = LoadPhantom(kPhantom, kAlice);
  const std::string session = Plan(volume);
  const v3::RenderSettings view = AView(volume);
  SetViewByInteract(session, view);
  // The export's frame: the view at the size of the stream's frames (512).
  const std::string capture_before = CapturePixels(session);
  const v3::Frame before = Still(session, view);
  ASSERT_EQ(before.slices_size(), 2);
  const std::string case_id = GetSessionCase(session);
  // The same view again: nothing is written.
  const int64_t modified = GetCase(case_id, kAlice).modified_unix_ms();
  std::this_thread::sleep_for(std::chrono::milliseconds(5));
  SetViewByInteract(session, view);
  EXPECT_EQ(GetCase(case_id, kAlice).modified_unix_ms(), modified);
  v3::RenderSettings watched;
  watched.set_preset("ct-vessels");
  WatchOneStill(session, watched);
  EXPECT_EQ(GetCase(case_id, kAlice).view().preset(), "ct-bone");

  Restart();
  const v3::CaseInfo info = GetCase(case_id, kAlice);
  ASSERT_TRUE(info.has_view());
  EXPECT_TRUE(google::protobuf::util::MessageDifferencer::Equals(info.view(), view))
      << info.view().DebugString();
  EXPECT_EQ(info.view().width(), 0);  // the client's own
  const v3::SessionInfo reopened = OpenCaseAsAlice(case_id);
  ASSERT_FALSE(reopened.session_id().empty());
  // Before any client asked for a frame: the session's own view.
  const std::string capture_after = CapturePixels(reopened.session_id());
  ASSERT_EQ(capture_after.size(), capture_before.size());
  double sum = 0.0;
  for (size_t i = 0; i < capture_before.size(); ++i) {
    sum += std::abs(int(uint8_t(capture_before[i])) - int(uint8_t(capture_after[i])));
  }
  const double capture_difference = sum / double(std::max<size_t>(1, capture_before.size()));
  const v3::Frame after = Still(reopened.session_id(), info.view());
  const double frame_difference = MeanDifference(before, after);
  std::printf("reopened view: frame mean difference %.4f / 255, capture %.4f / 255\n",
              frame_difference, capture_difference);
  EXPECT_LT(frame_difference, 1.0);
  EXPECT_LT(capture_difference, 1.0);
  ASSERT_EQ(after.slices_size(), 2);
  for (int i = 0; i < 2; ++i) {
    EXPECT_EQ(after.slices(i).view(), before.slices(i).view());
    EXPECT_LT(MeanDifference(before.slices(i).image(), after.slices(i).image()), 1.0);
  }
  // The capture shows the view, not the defaults: a crop and a clip cut away.
  const std::string capture_default = CapturePixelsOfNewSession(LoadPhantom(kPhantom, kAlice));
  ASSERT_EQ(capture_default.size(), capture_after.size());
  EXPECT_NE(capture_default, capture_after);

  // Export and import carry it; an archive's view is checked as settings.
  v3::ExportCaseRequest request;
  request.set_case_id(case_id);
  v3::CaseArchive archive;
  ASSERT_TRUE(stub_->ExportCase(Context(kAlice).get(), request, &archive).ok());
  EXPECT_TRUE(google::protobuf::util::MessageDifferencer::Equals(archive.view(), view));
  v3::ImportCaseRequest import;
  *import.mutable_archive() = archive;
  import.mutable_archive()->mutable_view()->set_width(300);  // a client's own: dropped
  v3::CaseInfo imported;
  ASSERT_TRUE(stub_->ImportCase(Context(kBob).get(), import, &imported).ok());
  EXPECT_TRUE(google::protobuf::util::MessageDifferencer::Equals(imported.view(), view));
  for (int i = 0; i < 16; ++i) *import.mutable_archive()->mutable_view()->add_clip() = view.clip(0);
  const grpc::Status refused = stub_->ImportCase(Context(kBob).get(), import, &imported);
  EXPECT_EQ(refused.error_code(), grpc::INVALID_ARGUMENT);
  EXPECT_NE(refused.error_message().find("archive.view"), std::string::npos)
      << refused.error_message();
}

// A full disk (a file size limit on the process, SIGXFSZ ignored) while
// the surgeon drags: the event that cannot be stored is refused with
// RESOURCE_EXHAUSTED, the session goes back to what the case holds, and a
// restart reopens exactly that.
TEST_F(CasesTest, AnEventTheDiskCannotHoldIsRefusedAndTheSessionKeepsWhatIsStored) {
  const v3::VolumeInfo volume = LoadPhantom(kPhantom, kAlice);
  const v3::SessionInfo opened = OpenSession(volume.volume_id(), kAlice);
  const std::string session = opened.session_id();
  ASSERT_TRUE(Manipulate(session, Grab(Centre(volume))).ok());
  ASSERT_TRUE(Manipulate(session, Drag(0, 0, 2)).ok());
  const fs::path wal = dir_ / "state" / "cases.sqlite-wal";
  ASSERT_TRUE(fs::exists(wal));
  rlimit old{};
  ASSERT_EQ(getrlimit(RLIMIT_FSIZE, &old), 0);
  signal(SIGXFSZ, SIG_IGN);
  rlimit limited = old;
  limited.rlim_cur = fs::file_size(wal) + 16 * 1024;
  ASSERT_EQ(setrlimit(RLIMIT_FSIZE, &limited), 0);
  int acknowledged = 2;
  grpc::Status refused;
  for (int i = 3; i <= 400; ++i) {
    refused = Manipulate(session, Drag(0, 0, 2 + 0.02 * i));
    if (!refused.ok()) break;
    ++acknowledged;
  }
  ASSERT_EQ(setrlimit(RLIMIT_FSIZE, &old), 0);
  signal(SIGXFSZ, SIG_DFL);
  std::printf("disk full after %d acknowledged events: %s\n", acknowledged,
              refused.error_message().c_str());
  ASSERT_EQ(refused.error_code(), grpc::RESOURCE_EXHAUSTED) << refused.error_message();
  EXPECT_NE(refused.error_message().find("was not applied"), std::string::npos);
  EXPECT_EQ(GetCase(opened.case_id(), kAlice).events(), acknowledged);
  const double live = Still(session).max_displacement_mm();
  // Room again: the plan goes on, and the case holds it.
  ASSERT_TRUE(Manipulate(session, Release(true)).ok());
  const double kept = Still(session).max_displacement_mm();
  Restart();
  v3::OpenCaseRequest open;
  open.set_case_id(opened.case_id());
  v3::SessionInfo reopened;
  ASSERT_TRUE(stub_->OpenCase(Context(kAlice).get(), open, &reopened).ok());
  EXPECT_EQ(GetCase(opened.case_id(), kAlice).events(), acknowledged + 1 /* the release */);
  EXPECT_NEAR(Still(reopened.session_id()).max_displacement_mm(), kept, 1e-3);
  EXPECT_GT(live, 0.5);
}

TEST(CasesOff, AServerWithADamagedCaseDatabaseDoesNotStartAndSaysWhy) {
  const fs::path dir = fs::temp_directory_path() / ("vpm-cases-damaged-" + std::to_string(::getpid()));
  fs::create_directories(dir);
  std::ofstream(dir / "cases.sqlite") << std::string(8192, 'x');
  ServerOptions options = SmallServerOptions();
  options.state_dir = dir.string();
  auto server = VpmServer::Create(options, SharedGpu());
  ASSERT_FALSE(server.ok());
  EXPECT_EQ(server.status().code(), absl::StatusCode::kDataLoss) << server.status();
  EXPECT_NE(server.status().message().find("--state-dir"), std::string::npos) << server.status();
  EXPECT_NE(server.status().message().find("damaged"), std::string::npos) << server.status();
  fs::remove_all(dir);
}

TEST(CasesOff, WithoutAStateDirThereAreNoCasesAndSessionsWorkAsBefore) {
  auto server = VpmServer::Create(SmallServerOptions(), SharedGpu());
  ASSERT_TRUE(server.ok()) << server.status();
  auto channel = grpc::CreateChannel("127.0.0.1:" + std::to_string((*server)->port()),
                                     grpc::InsecureChannelCredentials());
  auto stub = v3::Vpm::NewStub(channel);
  grpc::ClientContext context;
  context.AddMetadata("authorization", std::string("Bearer ") + kToken);
  v3::ListCasesResponse listed;
  const grpc::Status status = stub->ListCases(&context, {}, &listed);
  EXPECT_EQ(status.error_code(), grpc::FAILED_PRECONDITION);
  EXPECT_NE(status.error_message().find("--state-dir"), std::string::npos);
  (*server)->Shutdown(std::chrono::milliseconds(1000));
}

}  // namespace
}  // namespace vpm::service::testing
