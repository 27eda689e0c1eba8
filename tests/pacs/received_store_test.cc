#include "server/pacs/received_store.h"

#include <gtest/gtest.h>
#include <unistd.h>

#include <fstream>

#include "server/pacs/move_registry.h"
#include "server/pacs/study_query.h"

namespace vpm::pacs {
namespace {

namespace fs = std::filesystem;

TEST(ReceivedUid, RefusesWhatCouldNameAnotherPath) {
  for (const char* bad : {"", ".", "..", "../1.2", "1.2/3", "1.2.", ".1.2", "1.2\\3", "1.2 3",
                          "1.2.3\n", "1.2.a"}) {
    EXPECT_FALSE(CheckUid(bad, "uid").ok()) << bad;
  }
  EXPECT_FALSE(CheckUid(std::string(65, '1'), "uid").ok());
  EXPECT_TRUE(CheckUid(std::string(64, '1'), "uid").ok());
  EXPECT_TRUE(CheckUid("1.2.840.10008.5.1.4.1.1.2", "uid").ok());
}

TEST(ReceivedMatch, WildcardsAndDateRanges) {
  EXPECT_TRUE(MatchesWildcard("DOE^J*", "DOE^JOHN", true));
  EXPECT_TRUE(MatchesWildcard("doe^j*", "DOE^JOHN", true));
  EXPECT_FALSE(MatchesWildcard("doe^j*", "DOE^JOHN", false));
  EXPECT_TRUE(MatchesWildcard("D?E*N", "DOE^JOHN", false));
  EXPECT_TRUE(MatchesWildcard("*", "", false));
  EXPECT_FALSE(MatchesWildcard("DOE", "DOE^JOHN", false));
  EXPECT_TRUE(MatchesWildcard("*^*^*", "A^B^C", false));
  EXPECT_TRUE(MatchesDateRange("", ""));
  EXPECT_TRUE(MatchesDateRange("20240101-20241231", "20240611"));
  EXPECT_FALSE(MatchesDateRange("20250101-", "20240611"));
  EXPECT_TRUE(MatchesDateRange("-20240611", "20240611"));
  EXPECT_TRUE(MatchesDateRange("20240611", "20240611"));
  EXPECT_FALSE(MatchesDateRange("20240101-", ""));
}

class ReceivedStoreTest : public ::testing::Test {
 protected:
  void SetUp() override {
    root_ = fs::temp_directory_path() / ("vpm-received-" + std::to_string(::getpid()));
    fs::remove_all(root_);
  }
  void TearDown() override { fs::remove_all(root_); }

  std::unique_ptr<ReceivedStore> Open(int64_t max_bytes = 1 << 20) {
    auto store = ReceivedStore::Create({.root = root_, .max_bytes = max_bytes});
    EXPECT_TRUE(store.ok()) << store.status();
    return store.ok() ? std::move(*store) : nullptr;
  }
  // A series of `n` files of `bytes` each in `incoming`, reserved.
  ReceivedStore::SeriesFiles Files(ReceivedStore& store, const ReceivedStore::Incoming& incoming,
                                   const std::string& series, int n, int64_t bytes,
                                   const std::string& ae = "CT01") {
    ReceivedStore::SeriesFiles s;
    s.attributes = {.study_uid = "1.2.3", .series_uid = series, .patient_name = "DOE^JOHN",
                    .patient_id = "P1", .study_date = "20240611", .modality = "CT",
                    .series_description = "Abdomen", .series_number = 2};
    s.calling_ae = ae;
    for (int i = 0; i < n; ++i) {
      const fs::path path = incoming.folder() / (series + "-" + std::to_string(i));
      std::ofstream(path) << std::string(static_cast<size_t>(bytes), 'x');
      EXPECT_TRUE(store.Reserve(bytes).ok());
      s.files.emplace_back(path, series + "." + std::to_string(i + 1));
      s.bytes += bytes;
    }
    return s;
  }
  fs::path root_;
};

TEST_F(ReceivedStoreTest, CommittedSeriesIsSearchedListedAndOpened) {
  auto store = Open();
  auto incoming = store->BeginIncoming();
  ASSERT_TRUE(incoming.ok());
  Result<int64_t> added = store->Commit(Files(*store, **incoming, "1.2.3.4", 3, 100));
  ASSERT_TRUE(added.ok()) << added.status();
  EXPECT_EQ(*added, 3);
  EXPECT_EQ(store->stored_bytes(), 300);

  StudySearch found = store->Search({.patient_name = "doe^j*", .study_date = "20240101-"}, {});
  ASSERT_EQ(found.studies.size(), 1u);
  EXPECT_EQ(found.studies[0].study_uid, "1.2.3");
  EXPECT_EQ(found.studies[0].series_count, 1);
  EXPECT_EQ(found.studies[0].instance_count, 3);
  EXPECT_EQ(found.studies[0].modalities, std::vector<std::string>{"CT"});
  EXPECT_TRUE(store->Search({.modality = "MR"}, {}).studies.empty());
  EXPECT_TRUE(store->Search({}, {"OTHER"}).studies.empty());

  auto series = store->ListSeries("1.2.3", {});
  ASSERT_EQ(series.size(), 1u);
  EXPECT_EQ(series[0].instance_count, 3);
  auto lease = store->OpenSeries("1.2.3", "1.2.3.4", {"CT01"});
  ASSERT_TRUE(lease.ok());
  EXPECT_TRUE(fs::exists((*lease)->folder / "000003.dcm"));
  EXPECT_EQ((*lease)->folder.parent_path().filename(), "series");
  EXPECT_TRUE(absl::IsNotFound(store->OpenSeries("1.2.9", "1.2.3.4", {}).status()));
  EXPECT_TRUE(absl::IsNotFound(store->OpenSeries("1.2.3", "1.2.3.4", {"OTHER"}).status()));
}

TEST_F(ReceivedStoreTest, ASeriesSentAgainKeepsEachInstanceOnce) {
  auto store = Open();
  auto first = store->BeginIncoming();
  ASSERT_TRUE(store->Commit(Files(*store, **first, "1.2.3.4", 2, 10)).ok());
  auto second = store->BeginIncoming();
  Result<int64_t> added = store->Commit(Files(*store, **second, "1.2.3.4", 3, 10));
  ASSERT_TRUE(added.ok());
  EXPECT_EQ(*added, 1);
  EXPECT_EQ(store->ListSeries("1.2.3", {})[0].instance_count, 3);
  EXPECT_EQ(store->stored_bytes(), 30);
}

TEST_F(ReceivedStoreTest, BudgetCountsStoredAndReservedBytes) {
  auto store = Open(/*max_bytes=*/250);
  auto incoming = store->BeginIncoming();
  ASSERT_TRUE(store->Commit(Files(*store, **incoming, "1.2.3.4", 2, 100)).ok());
  EXPECT_TRUE(store->Reserve(50).ok());
  EXPECT_TRUE(absl::IsResourceExhausted(store->Reserve(1)));
  store->Release(50);
  EXPECT_TRUE(store->Reserve(50).ok());
}

TEST_F(ReceivedStoreTest, RestartKeepsCommittedSeriesAndDropsTheRest) {
  fs::path tmp;
  // A crash: the folder being received outlives its store, whose restart
  // below finds it (held, not leaked, so that its destructor runs only at
  // the end).
  std::unique_ptr<ReceivedStore::Incoming> crashed;
  {
    auto store = Open();
    auto incoming = store->BeginIncoming();
    ASSERT_TRUE(store->Commit(Files(*store, **incoming, "1.2.3.4", 2, 10)).ok());
    auto pending = store->BeginIncoming();
    tmp = (*pending)->folder();
    std::ofstream(tmp / "x") << "partial";
    crashed = *std::move(pending);
    fs::create_directories(root_ / "series" / "1.2.3.5");  // a commit cut short
  }
  EXPECT_TRUE(fs::exists(tmp));
  auto store = Open();
  EXPECT_FALSE(fs::exists(tmp));
  EXPECT_FALSE(fs::exists(root_ / "series" / "1.2.3.5"));
  EXPECT_EQ(store->ListSeries("1.2.3", {}).size(), 1u);
  EXPECT_EQ(store->stored_bytes(), 20);
}

TEST_F(ReceivedStoreTest, IncomingFolderGoesWithItsObject) {
  auto store = Open();
  fs::path folder;
  {
    auto incoming = store->BeginIncoming();
    folder = (*incoming)->folder();
    EXPECT_TRUE(fs::is_directory(folder));
  }
  EXPECT_FALSE(fs::exists(folder));
}

TEST(MoveRegistry, RoutesByPeerAndOriginatorAndCountsArrivals) {
  const fs::path folder =
      fs::temp_directory_path() / ("vpm-move-" + std::to_string(::getpid()));
  fs::create_directories(folder);
  MoveRegistry moves;
  auto expected = moves.Expect("1.2.3.4", "ORTHANC", "VPM", folder, 100);
  ASSERT_TRUE(expected.ok());
  EXPECT_TRUE(absl::IsFailedPrecondition(
      moves.Expect("1.2.3.4", "ORTHANC", "VPM", folder, 100).status()));
  EXPECT_EQ(moves.Route("1.2.3.4", "OTHER", ""), nullptr);
  EXPECT_EQ(moves.Route("1.2.3.5", "ORTHANC", ""), nullptr);
  EXPECT_EQ(moves.Route("1.2.3.4", "ORTHANC", "SOMEONE"), nullptr);
  auto sink = moves.Route("1.2.3.4", "ORTHANC", "VPM");
  ASSERT_NE(sink, nullptr);
  const fs::path file = folder / "in";
  std::ofstream(file) << std::string(60, 'x');
  EXPECT_TRUE(sink->Keep(file, 60).ok());
  EXPECT_TRUE(fs::exists(folder / "000001.dcm"));
  EXPECT_TRUE((*expected)->WaitFor(1, CancelToken(), 1.0).ok());
  EXPECT_TRUE(absl::IsDeadlineExceeded((*expected)->WaitFor(2, CancelToken(), 0.1)));
  std::ofstream(file) << std::string(60, 'x');
  EXPECT_TRUE(absl::IsResourceExhausted(sink->Keep(file, 60)));
  EXPECT_TRUE(absl::IsResourceExhausted((*expected)->failure()));
  expected->reset();
  EXPECT_EQ(moves.Route("1.2.3.4", "ORTHANC", ""), nullptr);
  fs::remove_all(folder);
}

}  // namespace
}  // namespace vpm::pacs
