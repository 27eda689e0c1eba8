#include "server/service/users_file.h"

#include <cctype>
#include <set>

#include "server/common/read_text_file.h"
#include "server/common/sha256.h"

namespace vpm::service {
namespace {

bool IsHexDigest(std::string_view s) {
  if (s.size() != 64) return false;
  for (char c : s) {
    if (!std::isxdigit(static_cast<unsigned char>(c))) return false;
  }
  return true;
}

// Splits on runs of spaces and tabs.
std::vector<std::string_view> Fields(std::string_view line) {
  std::vector<std::string_view> out;
  size_t i = 0;
  while (i < line.size()) {
    while (i < line.size() && (line[i] == ' ' || line[i] == '\t')) ++i;
    size_t j = i;
    while (j < line.size() && line[j] != ' ' && line[j] != '\t') ++j;
    if (j > i) out.push_back(line.substr(i, j - i));
    i = j;
  }
  return out;
}

}  // namespace

Status CheckUserName(std::string_view name) {
  if (name.empty() || name.size() > 64) {
    return absl::InvalidArgumentError(StrCat("user name '", name, "': 1 to 64 characters"));
  }
  for (char c : name) {
    if (!std::isalnum(static_cast<unsigned char>(c)) && c != '.' && c != '_' && c != '-') {
      return absl::InvalidArgumentError(
          StrCat("user name '", name, "': only letters, digits, '.', '_' and '-'"));
    }
  }
  return absl::OkStatus();
}

std::string HashToken(std::string_view token) {
  Sha256 sha;
  sha.Update({reinterpret_cast<const uint8_t*>(token.data()), token.size()});
  return sha.FinishHex();
}

Result<std::string> UsersFileLine(std::string_view name, std::string_view token) {
  RETURN_IF_ERROR(CheckUserName(name));
  if (token.size() < kMinTokenBytes) {
    // The length only: the token itself never goes into a message.
    return absl::InvalidArgumentError(StrCat(
        "the token has ", token.size(), " characters; give at least ", kMinTokenBytes,
        " (e.g. head -c 16 /dev/urandom | od -An -tx1 | tr -d ' \\n')"));
  }
  return StrCat(name, " ", HashToken(token));
}

Result<std::vector<UserCredential>> ParseUsersFile(std::string_view text,
                                                   std::string_view file_name) {
  std::vector<UserCredential> users;
  std::set<std::string, std::less<>> names, hashes;
  int line_number = 0;
  while (!text.empty()) {
    const size_t end = text.find('\n');
    std::string_view line = text.substr(0, end);
    text = end == std::string_view::npos ? std::string_view() : text.substr(end + 1);
    ++line_number;
    if (!line.empty() && line.back() == '\r') line.remove_suffix(1);
    const std::vector<std::string_view> fields = Fields(line);
    if (fields.empty() || fields[0].starts_with('#')) continue;
    const auto bad = [&](const std::string& why) {
      return absl::InvalidArgumentError(
          StrCat("--users ", file_name, " line ", line_number, ": ", why,
                 " (each line is 'NAME TOKEN-SHA256 [browse-data-root]'; `vpm-server --hash-token NAME` writes one)"));
    };
    if (fields.size() < 2) return bad(StrCat(fields.size(), " fields, not 2"));
    if (Status name = CheckUserName(fields[0]); !name.ok()) return bad(std::string(name.message()));
    if (!IsHexDigest(fields[1])) {
      return bad("the hash must be 64 hexadecimal digits (the SHA-256 of the token, not the token)");
    }
    std::string hash(fields[1]);
    for (char& c : hash) c = static_cast<char>(std::tolower(static_cast<unsigned char>(c)));
    if (!names.emplace(fields[0]).second) return bad(StrCat("user '", fields[0], "' given twice"));
    if (!hashes.emplace(hash).second) {
      return bad(StrCat("user '", fields[0], "' has the token of an earlier user"));
    }
    UserCredential user{std::string(fields[0]), std::move(hash)};
    for (size_t f = 2; f < fields.size(); ++f) {
      if (fields[f] != kBrowseDataRootPermission) {
        return bad(StrCat("unknown permission '", fields[f].substr(0, 64), "' (known: ",
                          kBrowseDataRootPermission, ")"));
      }
      user.browse_data_root = true;
    }
    users.push_back(std::move(user));
  }
  if (users.empty()) return absl::InvalidArgumentError(StrCat("--users ", file_name, ": no users"));
  return users;
}

Result<std::vector<UserCredential>> ReadUsersFile(const std::string& path) {
  ASSIGN_OR_RETURN(std::string text, ReadTextFile(path, "--users"));
  return ParseUsersFile(text, path);
}

}  // namespace vpm::service
