// ExportDicom's stream (export_dicom_reactor.h): progress first, one
// message per file, the summary last; the files are DICOM of the derived
// series and the capture; a client that stops reading ends the export and
// the server goes on; other users, absurd descriptions and an endpoint on a
// server without --pacs are refused.
#include <string>
#include <vector>

#include "tests/service/service_test_util.h"

namespace vpm::service::testing {
namespace {

class ExportDicomTest : public ServiceTest {
 protected:
  std::string Session() {
    const v3::VolumeInfo volume = LoadPhantom();
    const v3::SessionInfo session = OpenSession(volume.volume_id());
    v3::ManipulateRequest request;
    request.set_session_id(session.session_id());
    *request.mutable_event()->mutable_grab()->mutable_point_mm() = Centre(volume);
    v3::ManipulateResponse response;
    EXPECT_TRUE(stub_->Manipulate(Context().get(), request, &response).ok());
    *request.mutable_event()->mutable_drag()->mutable_offset_mm() = V(0, 0, 6);
    EXPECT_TRUE(stub_->Manipulate(Context().get(), request, &response).ok());
    return session.session_id();
  }
  grpc::Status Export(const v3::ExportDicomRequest& request, std::vector<v3::ExportDicomPart>* parts,
                      const std::string& token = kToken) {
    auto context = Context(token);
    auto reader = stub_->ExportDicom(context.get(), request);
    v3::ExportDicomPart part;
    while (reader->Read(&part)) parts->push_back(part);
    return reader->Finish();
  }
};

TEST_F(ExportDicomTest, ProgressThenOneFilePerSliceAndTheCaptureThenTheSummary) {
  v3::ExportDicomRequest request;
  request.set_session_id(Session());
  std::vector<v3::ExportDicomPart> parts;
  const grpc::Status status = Export(request, &parts);
  ASSERT_TRUE(status.ok()) << status.error_message();
  ASSERT_FALSE(parts.empty());
  ASSERT_TRUE(parts.back().has_summary());
  const v3::ExportDicomSummary& summary = parts.back().summary();
  EXPECT_EQ(summary.instances(), 48 + 1);
  EXPECT_GT(summary.max_displacement_mm(), 1.0);
  EXPECT_TRUE(summary.endpoint().empty());
  EXPECT_EQ(parts.front().stage(), "warping");
  int files = 0, captures = 0;
  int64_t bytes = 0;
  bool file_seen = false;
  for (const v3::ExportDicomPart& p : parts) {
    if (p.file_name().empty()) {
      EXPECT_FALSE(file_seen && !p.has_summary()) << "progress after the files";
      continue;
    }
    file_seen = true;
    ++files;
    captures += p.file_name().starts_with("capture/");
    bytes += int64_t(p.data().size());
    ASSERT_GT(p.data().size(), 132u);
    EXPECT_EQ(p.data().substr(128, 4), "DICM") << p.file_name();
    EXPECT_TRUE(p.file_name().starts_with("derived/") || p.file_name().starts_with("capture/"));
    if (p.file_name().starts_with("derived/")) {
      EXPECT_NE(p.data().find(summary.derived_series_uid()), std::string::npos);
    }
  }
  EXPECT_EQ(files, summary.instances());
  EXPECT_EQ(captures, 1);
  EXPECT_EQ(bytes, summary.bytes());
}

TEST_F(ExportDicomTest, AClientThatStopsReadingEndsTheExportAndTheServerGoesOn) {
  const std::string session = Session();
  for (int round = 0; round < 3; ++round) {
    v3::ExportDicomRequest request;
    request.set_session_id(session);
    auto context = Context();
    auto reader = stub_->ExportDicom(context.get(), request);
    v3::ExportDicomPart part;
    int files = 0;
    while (files < 2 && reader->Read(&part)) files += !part.file_name().empty();
    context->TryCancel();
    while (reader->Read(&part)) {
    }
    EXPECT_EQ(reader->Finish().error_code(), grpc::CANCELLED);
  }
  // The stream slots came back: a whole export still runs.
  v3::ExportDicomRequest request;
  request.set_session_id(session);
  std::vector<v3::ExportDicomPart> parts;
  EXPECT_TRUE(Export(request, &parts).ok());
  EXPECT_TRUE(!parts.empty() && parts.back().has_summary());
}

TEST_F(ExportDicomTest, RefusesOthersAbsurdRequestsAndEndpointsWithoutAPacs) {
  v3::ExportDicomRequest request;
  std::vector<v3::ExportDicomPart> parts;
  EXPECT_EQ(Export(request, &parts).error_code(), grpc::INVALID_ARGUMENT);
  request.set_session_id(Session());
  request.set_series_description(std::string(65, 'x'));
  EXPECT_EQ(Export(request, &parts).error_code(), grpc::INVALID_ARGUMENT);
  request.clear_series_description();
  request.set_endpoint("orthanc");
  EXPECT_EQ(Export(request, &parts).error_code(), grpc::FAILED_PRECONDITION);
  request.clear_endpoint();
  request.set_session_id("ses-nope");
  EXPECT_EQ(Export(request, &parts).error_code(), grpc::NOT_FOUND);
  EXPECT_TRUE(parts.empty() || !parts.back().has_summary());
}

}  // namespace
}  // namespace vpm::service::testing
