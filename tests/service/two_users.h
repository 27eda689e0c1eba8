// A server with two users, alice and bob (a users file of their token
// hashes), for the tests that one user cannot hurt the other: streams that
// end when access ends (stream_access_test.cc), cancelled work
// (cancel_work_test.cc), per-user caps (fair_share_test.cc).
#pragma once

#include <filesystem>
#include <fstream>
#include <string>

#include <unistd.h>

#include "server/service/users_file.h"
#include "tests/service/service_test_util.h"

namespace vpm::service::testing {

inline constexpr char kAliceToken[] = "alice-secret-token";
inline constexpr char kBobToken[] = "bob-secret-token";

class TwoUsersTest : public ServiceTest {
 protected:
  // Starts the server with `options` and the users alice and bob.
  void StartWithUsers(ServerOptions options) {
    dir_ = std::filesystem::temp_directory_path() /
           ("vpm-two-users-" + std::to_string(getpid()));
    std::filesystem::create_directories(dir_);
    const std::filesystem::path users = dir_ / "users.txt";
    std::ofstream(users) << "alice " << HashToken(kAliceToken) << "\nbob "
                         << HashToken(kBobToken) << "\n";
    options.token.clear();
    options.users_file = users.string();
    StartServer(options);
  }
  void SetUp() override { StartWithUsers(SmallServerOptions()); }
  void TearDown() override {
    ServiceTest::TearDown();
    std::filesystem::remove_all(dir_);
  }

  std::filesystem::path dir_;
};

}  // namespace vpm::service::testing
