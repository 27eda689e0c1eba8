// The data root is a jail (issue 25, points 6 and 9): every file a load opens
// on a client's behalf (a DICOM folder's members, a .mhd's data file) must
// resolve inside the root; only regular files are opened, so a FIFO is an
// error at once, never a hung worker; errors name files relative to the
// root; a DICOM folder's series can be picked with ?series=UID.
#include <fcntl.h>
#include <sys/stat.h>
#include <unistd.h>

#include <algorithm>
#include <atomic>
#include <chrono>
#include <fstream>
#include <future>
#include <thread>

#include "server/io/list_dicom_series.h"
#include "tests/service/service_test_util.h"

namespace vpm::service::testing {
namespace {

namespace fs = std::filesystem;
using Clock = std::chrono::steady_clock;

double ElapsedSince(Clock::time_point start) {
  return std::chrono::duration<double>(Clock::now() - start).count();
}


void WriteText(const fs::path& path, const std::string& text) { std::ofstream(path) << text; }

// A MetaImage header of a 2 x 2 x 2 int16 volume whose voxels are `data`.
std::string MhdHeader(const std::string& data) {
  return "ObjectType = Image\nNDims = 3\nDimSize = 2 2 2\nElementType = MET_SHORT\n"
         "ElementSpacing = 1 1 1\nElementByteOrderMSB = False\nElementDataFile = " +
         data + "\n";
}

class JailTest : public ServiceTest {
 protected:
  void SetUp() override {
    const std::string tag = std::to_string(::getpid());
    root_ = fs::temp_directory_path() / ("vpm-jail-root-" + tag);
    outside_ = fs::temp_directory_path() / ("vpm-jail-outside-" + tag);
    fs::remove_all(root_);
    fs::remove_all(outside_);
    fs::create_directories(root_ / "dicom");
    fs::create_directories(outside_);
    // Eight int16 voxels, inside and outside the root.
    const std::string voxels(16, '\1');
    WriteText(root_ / "inside.raw", voxels);
    WriteText(outside_ / "secret.raw", voxels);
    WriteText(root_ / "good.mhd", MhdHeader("inside.raw"));
    fs::create_symlink(outside_ / "secret.raw", root_ / "link.raw");
    WriteText(root_ / "linked.mhd", MhdHeader("link.raw"));
    WriteText(root_ / "dotdot.mhd", MhdHeader("../" + outside_.filename().string() + "/secret.raw"));
    // Three slices of the repository's CT, and a member leading out.
    std::vector<fs::path> slices;
    for (const auto& entry : fs::directory_iterator(SourceData() / "ct-philips-tilt")) {
      if (entry.path().filename().string().starts_with("I")) slices.push_back(entry.path());
    }
    std::sort(slices.begin(), slices.end());
    ASSERT_GE(slices.size(), 3u);
    for (size_t i = 0; i < 3; ++i) {
      fs::copy_file(slices[i], root_ / "dicom" / slices[i].filename());
    }
    WriteText(outside_ / "report.dcm", std::string(4096, '\0') + "DICM");
    fs::create_symlink(outside_ / "report.dcm", root_ / "dicom" / "zz-escape.dcm");
    ASSERT_EQ(::mkfifo((root_ / "x.nii").c_str(), 0600), 0);
    ASSERT_EQ(::mkfifo((root_ / "y.nii").c_str(), 0600), 0);
    ServerOptions options = SmallServerOptions();
    options.data_root = root_.string();
    StartServer(options);
  }
  void TearDown() override {
    ServiceTest::TearDown();
    fs::remove_all(root_);
    fs::remove_all(outside_);
  }
  grpc::Status Load(const std::string& source, v3::VolumeInfo* info = nullptr, int deadline_s = 60) {
    v3::LoadVolumeRequest request;
    request.set_source(source);
    v3::VolumeInfo ignored;
    return stub_->LoadVolume(Context(kToken, deadline_s).get(), request,
                             info != nullptr ? info : &ignored);
  }
  // The message must not name the server's folders.
  void ExpectNoServerPaths(const grpc::Status& status) {
    EXPECT_EQ(status.error_message().find(root_.string()), std::string::npos)
        << status.error_message();
    EXPECT_EQ(status.error_message().find(outside_.string()), std::string::npos)
        << status.error_message();
  }
  fs::path root_, outside_;
};

TEST_F(JailTest, MetaImageDataFileMustStayInsideTheRoot) {
  v3::VolumeInfo info;
  grpc::Status good = Load("good.mhd", &info);
  ASSERT_TRUE(good.ok()) << good.error_message();
  EXPECT_EQ(info.dims(0), 2);
  grpc::Status linked = Load("linked.mhd");
  EXPECT_EQ(linked.error_code(), grpc::PERMISSION_DENIED) << linked.error_message();
  EXPECT_NE(linked.error_message().find("link.raw"), std::string::npos) << linked.error_message();
  ExpectNoServerPaths(linked);
  grpc::Status dotdot = Load("dotdot.mhd");
  EXPECT_EQ(dotdot.error_code(), grpc::INVALID_ARGUMENT) << dotdot.error_message();
  ExpectNoServerPaths(dotdot);
}

TEST_F(JailTest, DicomFolderMemberLeadingOutsideIsRefused) {
  grpc::Status status = Load("dicom");
  EXPECT_EQ(status.error_code(), grpc::PERMISSION_DENIED) << status.error_message();
  EXPECT_NE(status.error_message().find("zz-escape.dcm"), std::string::npos)
      << status.error_message();
  ExpectNoServerPaths(status);
  // Without the escaping member the same folder loads.
  fs::remove(root_ / "dicom" / "zz-escape.dcm");
  grpc::Status again = Load("dicom");
  EXPECT_TRUE(again.ok()) << again.error_message();
}

// Issue 25 case 8: a FIFO named *.nii used to hang a request thread for
// good. If it ever blocks again, a writer opened after 5 s frees the thread
// so that the test fails instead of hanging.
TEST_F(JailTest, FifoIsAnErrorAtOnceAndTheServerStaysResponsive) {
  std::atomic<bool> done{false};
  std::thread rescue([&] {
    for (int i = 0; i < 50 && !done; ++i) std::this_thread::sleep_for(std::chrono::milliseconds(100));
    for (const char* name : {"x.nii", "y.nii"}) {
      const int fd = ::open((root_ / name).c_str(), O_WRONLY | O_NONBLOCK);
      if (fd >= 0) ::close(fd);
    }
  });
  const auto start = Clock::now();
  // Two at once: the request pool has two threads.
  auto x = std::async(std::launch::async, [&] { return Load("x.nii", nullptr, 10); });
  auto y = std::async(std::launch::async, [&] { return Load("y.nii", nullptr, 10); });
  const grpc::Status sx = x.get(), sy = y.get();
  const double waited_s = ElapsedSince(start);
  done = true;
  rescue.join();
  EXPECT_LT(waited_s, 1.0);
  for (const grpc::Status& s : {sx, sy}) {
    EXPECT_EQ(s.error_code(), grpc::INVALID_ARGUMENT) << s.error_message();
    EXPECT_NE(s.error_message().find("FIFO"), std::string::npos) << s.error_message();
    ExpectNoServerPaths(s);
  }
  // The pools are free: a load and a listing answer at once.
  const auto after = Clock::now();
  v3::VolumeInfo info;
  grpc::Status phantom = Load(kPhantom, &info, 30);
  EXPECT_TRUE(phantom.ok()) << phantom.error_message();
  v3::ListVolumesResponse list;
  EXPECT_TRUE(stub_->ListVolumes(Context(kToken, 5).get(), {}, &list).ok());
  EXPECT_LT(ElapsedSince(after), 10.0);
}

TEST_F(JailTest, NameTooLongIsInvalidArgument) {
  grpc::Status component = Load(std::string(300, 'a') + ".nii");
  EXPECT_EQ(component.error_code(), grpc::INVALID_ARGUMENT) << component.error_message();
  std::string deep;
  while (deep.size() < 5000) deep += "abcdefgh/";
  grpc::Status whole = Load(deep + "x.nii");
  EXPECT_EQ(whole.error_code(), grpc::INVALID_ARGUMENT) << whole.error_message();
}

TEST_F(JailTest, ErrorsNameFilesRelativeToTheRoot) {
  WriteText(root_ / "broken.nii", "not a NIfTI file at all");
  grpc::Status status = Load("broken.nii");
  EXPECT_EQ(status.error_code(), grpc::INVALID_ARGUMENT) << status.error_message();
  EXPECT_NE(status.error_message().find("broken.nii"), std::string::npos)
      << status.error_message();
  ExpectNoServerPaths(status);
}

// `FOLDER?series=UID` picks one series of a DICOM folder through LoadVolume.
TEST_F(ServiceTest, LoadVolume_DicomFolderWithSeriesQuery) {
  server_->Shutdown(std::chrono::milliseconds(2000));
  ServerOptions options = SmallServerOptions();
  options.data_root = SourceData().string();
  StartServer(options);
  auto series = ListDicomSeries(SourceData() / "ct-philips-tilt", {});
  ASSERT_TRUE(series.ok()) << series.status();
  ASSERT_FALSE(series->empty());
  const std::string uid = series->front().uid;
  ASSERT_FALSE(uid.empty());
  v3::LoadVolumeRequest request;
  request.set_source("ct-philips-tilt?series=" + uid);
  v3::VolumeInfo info;
  grpc::Status status = stub_->LoadVolume(Context().get(), request, &info);
  ASSERT_TRUE(status.ok()) << status.error_message();
  EXPECT_EQ(info.source(), "ct-philips-tilt?series=" + uid);
  EXPECT_GT(info.dims(2), 1);
  // An unknown series is the client's mistake, said without the root.
  request.set_source("ct-philips-tilt?series=1.2.3.4.5");
  status = stub_->LoadVolume(Context().get(), request, &info);
  EXPECT_FALSE(status.ok());
  EXPECT_NE(status.error_code(), grpc::INTERNAL);
  EXPECT_EQ(status.error_message().find(SourceData().string()), std::string::npos)
      << status.error_message();
}

}  // namespace
}  // namespace vpm::service::testing
