#include "server/pacs/study_query.h"

#include <gtest/gtest.h>

#include "server/pacs/dicom_json.h"
#include "server/pacs/pacs_source.h"

namespace vpm::pacs {
namespace {

TEST(StudyQuery, EncodesFiltersAndPaging) {
  StudyQuery q{.patient_name = "DOE^J*", .study_date = "20240101-20241231", .modality = "CT"};
  const std::string text = StudyQueryString(q, 25, 50);
  EXPECT_NE(text.find("PatientName=DOE^J*&"), std::string::npos) << text;
  // What would break the query is encoded.
  EXPECT_NE(StudyQueryString({.patient_id = "A&B=C D#+%"}, 1, 0).find("PatientID=A%26B%3DC%20D%23%2B%25&"),
            std::string::npos);
  EXPECT_NE(text.find("StudyDate=20240101-20241231&"), std::string::npos) << text;
  EXPECT_NE(text.find("ModalitiesInStudy=CT&"), std::string::npos) << text;
  EXPECT_NE(text.find("limit=25&offset=50"), std::string::npos) << text;
  EXPECT_EQ(text.find("PatientID"), std::string::npos) << text;
  EXPECT_EQ(StudyQueryFilters(q), "PatientName,StudyDate,ModalitiesInStudy");
}

TEST(StudyQuery, ChecksFields) {
  EXPECT_TRUE(CheckStudyQuery({.study_date = "20240101-"}).ok());
  EXPECT_TRUE(CheckStudyQuery({.study_date = "-20240101"}).ok());
  EXPECT_TRUE(CheckStudyQuery({.patient_birth_date = "19700101"}).ok());
  for (const StudyQuery& bad : std::vector<StudyQuery>{{.study_date = "2024"},
                                                       {.study_date = "20240101-2024"},
                                                       {.study_date = "-"},
                                                       {.study_date = "20240101-20240102-20240103"},
                                                       {.modality = "ct"},
                                                       {.patient_name = "a\nb"},
                                                       {.patient_id = std::string(65, 'x')},
                                                       {.limit = 0},
                                                       {.limit = 1001},
                                                       {.patient_name = "a\\b"}}) {
    EXPECT_TRUE(absl::IsInvalidArgument(CheckStudyQuery(bad)));
  }
  // Errors name the field, never the value.
  Status s = CheckStudyQuery({.patient_name = "SECRET\x01NAME"});
  EXPECT_EQ(s.message().find("SECRET"), std::string_view::npos);
}

TEST(StudyQuery, ChecksUids) {
  EXPECT_TRUE(CheckUid("1.2.840.10008.5.1.4.1.1.2", "x").ok());
  for (const std::string& bad :
       std::vector<std::string>{"", ".1", "1.", "1.2/3", "../1", std::string(65, '1'), "1.2a"}) {
    EXPECT_TRUE(absl::IsInvalidArgument(CheckUid(bad, "x"))) << bad;
  }
}

TEST(PacsSource, ParsesAndRejects) {
  auto s = ParsePacsSource("pacs:orthanc/1.2.3/1.2.3.4");
  ASSERT_TRUE(s.ok()) << s.status();
  EXPECT_EQ(s->endpoint, "orthanc");
  EXPECT_EQ(s->study_uid, "1.2.3");
  EXPECT_EQ(s->series_uid, "1.2.3.4");
  EXPECT_EQ(s->stack, 0);
  s = ParsePacsSource("pacs:orthanc/1.2.3/1.2.3.4?stack=2");
  ASSERT_TRUE(s.ok()) << s.status();
  EXPECT_EQ(s->series_uid, "1.2.3.4");
  EXPECT_EQ(s->stack, 2);
  for (const char* bad :
       {"pacs:orthanc/1.2.3", "pacs:/1/2", "pacs:o/1/2/3", "pacs:o/../2", "pacs:.o/1/2",
        "file:o/1/2", "pacs:o/1/2?stack=0", "pacs:o/1/2?stack=", "pacs:o/1/2?series=2",
        "pacs:o/1/2?stack=2&stack=3", "pacs:o/1?stack=2/2"}) {
    EXPECT_TRUE(absl::IsInvalidArgument(ParsePacsSource(bad).status())) << bad;
  }
}

TEST(DicomJson, ParsesStudiesAndSeries) {
  auto studies = ParseStudies(R"([
    {"0020000D": {"vr": "UI", "Value": ["1.2.3"]},
     "00100010": {"vr": "PN", "Value": [{"Alphabetic": "Doe^John"}]},
     "00100020": {"vr": "LO", "Value": ["P1"]},
     "00080061": {"vr": "CS", "Value": ["CT", "SR"]},
     "00201206": {"vr": "IS", "Value": ["3"]},
     "00201208": {"vr": "IS", "Value": [120]}},
    {"0020000D": {"vr": "UI"}},
    {"0020000D": {"vr": "UI", "Value": ["bad/uid"]}}])");
  ASSERT_TRUE(studies.ok()) << studies.status();
  ASSERT_EQ(studies->size(), 1u);  // entries without a valid UID are skipped
  EXPECT_EQ((*studies)[0].patient_name, "Doe^John");
  EXPECT_EQ((*studies)[0].modalities, (std::vector<std::string>{"CT", "SR"}));
  EXPECT_EQ((*studies)[0].series_count, 3);
  EXPECT_EQ((*studies)[0].instance_count, 120);
  auto series = ParseSeries(R"([{"0020000E": {"vr": "UI", "Value": ["1.2.3.4"]},
     "00080060": {"vr": "CS", "Value": ["CT"]}, "0008103E": {"vr": "LO", "Value": ["Abdomen"]},
     "00180015": {"vr": "CS", "Value": ["ABDOMEN"]}, "00201209": {"vr": "IS", "Value": [112]}}])");
  ASSERT_TRUE(series.ok()) << series.status();
  ASSERT_EQ(series->size(), 1u);
  EXPECT_EQ((*series)[0].body_part, "ABDOMEN");
  EXPECT_EQ((*series)[0].instance_count, 112);
  EXPECT_TRUE(ParseStudies("").ok());
  EXPECT_TRUE(absl::IsInvalidArgument(ParseStudies("{}").status()));
  EXPECT_TRUE(absl::IsInvalidArgument(ParseStudies("[1]").status()));
  EXPECT_TRUE(absl::IsInvalidArgument(ParseSeries("<html>").status()));
}

}  // namespace
}  // namespace vpm::pacs
