// What the clients put on every call and make of a stream's end: the
// x-vpm-session key (session_key.h) and FromStreamEnd / SessionLost
// (server_connection.h), which turn a stream a balancer cut into
// UNAVAILABLE.
#include <cstdlib>

#include <gtest/gtest.h>

#include "client/common/server_connection.h"
#include "client/common/session_key.h"

namespace vpm::cli {
namespace {

TEST(SessionKey, EnvironmentWinsElseOneKeyPerUserAndHost) {
  ::unsetenv("VPM_SESSION_KEY");
  const std::string key = DefaultSessionKey();
  ASSERT_EQ(key.size(), 5u + 16u) << key;
  EXPECT_EQ(key.rfind("user-", 0), 0u) << key;
  EXPECT_EQ(key.find_first_not_of("0123456789abcdef", 5), std::string::npos) << key;
  EXPECT_EQ(DefaultSessionKey(), key) << "not stable across runs of one user";
  ::setenv("USER", "someone-else", 1);
  EXPECT_NE(DefaultSessionKey(), key) << "another user shares the key";
  ::setenv("VPM_SESSION_KEY", "workspace-7", 1);
  EXPECT_EQ(DefaultSessionKey(), "workspace-7");
  ::unsetenv("VPM_SESSION_KEY");
}

TEST(ServerConnection, SendsTheSessionKeyGivenOrTheDefault) {
  ServerFlags flags;
  flags.address = "127.0.0.1:1";
  flags.session_key = "k-1";
  auto given = ServerConnection::Connect(flags);
  ASSERT_TRUE(given.ok()) << given.status();
  EXPECT_EQ(given->session_key(), "k-1");
  flags.session_key.clear();
  auto fallback = ServerConnection::Connect(flags);
  ASSERT_TRUE(fallback.ok()) << fallback.status();
  EXPECT_EQ(fallback->session_key(), DefaultSessionKey());
}

TEST(FromStreamEnd, AStreamTheBalancerCutIsUnavailable) {
  const Status no_trailers =
      FromStreamEnd(grpc::Status(grpc::StatusCode::UNKNOWN, "No status received"));
  EXPECT_TRUE(absl::IsUnavailable(no_trailers)) << no_trailers;
  EXPECT_NE(no_trailers.message().find("replica"), std::string::npos) << no_trailers;
  const Status reset = FromStreamEnd(
      grpc::Status(grpc::StatusCode::CANCELLED, "Received RST_STREAM with error code 8"));
  EXPECT_TRUE(absl::IsUnavailable(reset)) << reset;
  EXPECT_TRUE(SessionLost(no_trailers));
  // What the server says itself is kept.
  EXPECT_TRUE(absl::IsUnknown(FromStreamEnd(grpc::Status(grpc::StatusCode::UNKNOWN, "other"))));
  EXPECT_TRUE(absl::IsCancelled(FromStreamEnd(grpc::Status(grpc::StatusCode::CANCELLED, "x"))));
  const Status refused =
      FromStreamEnd(grpc::Status(grpc::StatusCode::INVALID_ARGUMENT, "grab: outside"));
  EXPECT_TRUE(absl::IsInvalidArgument(refused));
  EXPECT_FALSE(SessionLost(refused));
  EXPECT_TRUE(SessionLost(absl::NotFoundError("session_id: no session 'ses-1a2b3c4d-1'")));
  EXPECT_TRUE(FromStreamEnd(grpc::Status::OK).ok());
}

}  // namespace
}  // namespace vpm::cli
