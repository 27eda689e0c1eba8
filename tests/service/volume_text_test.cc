// Text from files reaches clients as valid UTF-8: a DICOM folder of the
// data root whose SeriesDescription is Latin-1 without a declared character
// set, and whose file names (named in a note about a gap) are not UTF-8,
// loads through LoadVolume; before, the note's bytes made the C++ client
// refuse the answer ("No message returned for unary request").
#include <filesystem>
#include <string>

#include "tests/io/dicom_test_util.h"
#include "tests/service/two_users.h"

namespace vpm::service::testing {
namespace {

namespace fs = std::filesystem;

class VolumeTextTest : public TwoUsersTest {
 protected:
  void SetUp() override {
    root_ = fs::temp_directory_path() / ("vpm-volume-text-" + std::to_string(::getpid()));
    fs::remove_all(root_);
    fs::create_directories(root_ / "latin");
    // Three slices at z = 0, 1 and 10 mm: the 9 mm gap is over five times
    // the smallest, so a note names the two files around it.
    ::vpm::testing::DicomSliceSpec s;
    s.series_description =
        "Sch\xe4"
        "del";  // ISO 8859-1, no SpecificCharacterSet
    int k = 0;
    for (double z : {0.0, 1.0, 10.0}) {
      s.position_mm = glm::dvec3(0.0, 0.0, z);
      const std::string name =
          "sl\xe4"
          "ce" +
          std::to_string(k++) + ".dcm";  // not UTF-8
      ASSERT_TRUE(::vpm::testing::WriteDicomSlice(root_ / "latin" / name, s));
    }
    ServerOptions options = SmallServerOptions();
    options.data_root = root_.string();
    StartWithUsers(options);
  }
  void TearDown() override {
    TwoUsersTest::TearDown();
    fs::remove_all(root_);
  }
  fs::path root_;
};

TEST_F(VolumeTextTest, ALatin1FolderLoadsAndItsNotesAreUtf8) {
  v3::LoadVolumeRequest request;
  request.set_source("latin");
  v3::VolumeInfo info;
  const grpc::Status status = stub_->LoadVolume(Context(kAliceToken).get(), request, &info);
  ASSERT_TRUE(status.ok()) << status.error_message();
  std::string notes;
  for (const std::string& note : info.notes()) notes += note + "\n";
  // The file names' 0xE4 arrives as "ä" (U+00E4, bytes C3 A4).
  EXPECT_NE(notes.find("sl\xc3\xa4"
                       "ce1.dcm and sl\xc3\xa4"
                       "ce2.dcm"),
            std::string::npos)
      << notes;
  v3::GetVolumeRequest get;
  get.set_volume_id(info.volume_id());
  v3::VolumeInfo again;
  ASSERT_TRUE(stub_->GetVolume(Context(kAliceToken).get(), get, &again).ok());
  EXPECT_EQ(again.notes_size(), info.notes_size());
}

}  // namespace
}  // namespace vpm::service::testing
