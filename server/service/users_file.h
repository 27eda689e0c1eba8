// The users file of --users: one user a line, `NAME TOKEN-SHA256`, where
// NAME is 1 to 64 of [A-Za-z0-9._-] and TOKEN-SHA256 the 64 hexadecimal
// digits of the SHA-256 of the user's bearer token (`vpm-server
// --hash-token NAME` reads the token on stdin and prints the line). Blank
// lines and lines starting with '#' are skipped. Permissions may follow the
// hash, separated by spaces: `browse-data-root` lets the user list the
// server's --data-root (ListDataRoot); none are given by default. The server never holds a
// user's token, only its hash.
#pragma once

#include <string>
#include <string_view>
#include <vector>

#include "server/common/status.h"

namespace vpm::service {

struct UserCredential {
  std::string name;
  std::string token_sha256_hex;  // 64 lower-case hexadecimal digits
  bool browse_data_root = false;  // the permission `browse-data-root`
};

// The permissions a users file line may give, after the hash.
inline constexpr char kBrowseDataRootPermission[] = "browse-data-root";

// InvalidArgument naming the file and line for a malformed line, a bad
// name or hash, an unknown permission, a name given twice or a hash given twice (two users with one
// token could not be told apart); also for a file without any user.
Result<std::vector<UserCredential>> ParseUsersFile(std::string_view text,
                                                   std::string_view file_name);
Result<std::vector<UserCredential>> ReadUsersFile(const std::string& path);

// InvalidArgument unless `name` is 1 to 64 of [A-Za-z0-9._-].
Status CheckUserName(std::string_view name);
// Lower-case hex SHA-256 of `token`.
std::string HashToken(std::string_view token);
// The shortest token `--hash-token` takes, characters: a guessable token is
// refused before it is written into a users file.
inline constexpr size_t kMinTokenBytes = 16;
// The line of the users file for `name` and `token`, without a newline.
// InvalidArgument for a bad name or a token shorter than kMinTokenBytes.
Result<std::string> UsersFileLine(std::string_view name, std::string_view token);

}  // namespace vpm::service
