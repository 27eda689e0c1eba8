#include "server/pacs/pacs_endpoint.h"

#include <algorithm>
#include <fstream>
#include <set>
#include <sstream>

#include <nlohmann/json.hpp>

#include "server/pacs/dimse_address.h"

namespace vpm::pacs {
namespace {

using nlohmann::json;

Status ParseUsers(const json& entry, const std::string& named, PacsEndpoint* endpoint);

const std::set<std::string> kKeys = {"name",          "dicomweb",          "username",
                                     "password_file", "bearer_token_file", "ca_file",
                                     "users",         "page_size",         "dimse",
                                     "calling_aet", "retrieve",   "move_destination",
                                     "receive",     "from"};

// "retrieve" and "move_destination" of a "dimse" entry.
Status ParseRetrieveKeys(const json& entry, const std::string& named, PacsEndpoint* endpoint) {
  if (entry.contains("retrieve")) {
    const json& how = entry["retrieve"];
    if (!how.is_string() || (how != "get" && how != "move")) {
      return absl::InvalidArgumentError(StrCat(named, ": \"retrieve\" is \"get\" or \"move\""));
    }
    endpoint->retrieve_by_move = how == "move";
  }
  if (entry.contains("move_destination")) {
    if (!endpoint->retrieve_by_move) {
      return absl::InvalidArgumentError(
          StrCat(named, ": \"move_destination\" goes with \"retrieve\": \"move\""));
    }
    if (!entry["move_destination"].is_string() ||
        !CheckAeTitle(entry["move_destination"].get<std::string>()).ok()) {
      return absl::InvalidArgumentError(StrCat(
          named, ": \"move_destination\" must be an AE title (1-16 printable characters)"));
    }
    endpoint->move_destination = entry["move_destination"].get<std::string>();
  }
  if (endpoint->retrieve_by_move && endpoint->move_destination.empty()) {
    return absl::InvalidArgumentError(StrCat(
        named, ": \"retrieve\": \"move\" needs \"move_destination\", the AE title under which "
               "the PACS knows vpm's --dicom-listen node"));
  }
  return absl::OkStatus();
}

// An entry {"name", "receive": true, "from": [AE titles], "users"}: the
// series sent to vpm's own node.
Status ParseReceiveKeys(const json& entry, const std::string& named, PacsEndpoint* endpoint) {
  for (const auto& [key, value] : entry.items()) {
    if (key != "name" && key != "receive" && key != "from" && key != "users") {
      return absl::InvalidArgumentError(StrCat(
          named, ": \"", key.substr(0, 40), "\" does not go with \"receive\" (name, receive, "
                 "from, users)"));
    }
  }
  if (entry["receive"] != true) {
    return absl::InvalidArgumentError(StrCat(named, ": \"receive\" is true or absent"));
  }
  endpoint->receive = true;
  if (entry.contains("from")) {
    if (!entry["from"].is_array()) {
      return absl::InvalidArgumentError(StrCat(named, ": \"from\" must list AE titles"));
    }
    for (const json& ae : entry["from"]) {
      if (!ae.is_string() || !CheckAeTitle(ae.get<std::string>()).ok()) {
        return absl::InvalidArgumentError(
            StrCat(named, ": \"from\" must list AE titles (1-16 printable characters)"));
      }
      endpoint->receive_from.push_back(ae.get<std::string>());
    }
  }
  return ParseUsers(entry, named, endpoint);
}

// The "dimse" and "calling_aet" keys of an entry without "dicomweb".
Status ParseDimseKeys(const json& entry, const std::string& named, PacsEndpoint* endpoint) {
  for (const char* key : {"username", "password_file", "bearer_token_file", "ca_file"}) {
    if (entry.contains(key)) {
      return absl::InvalidArgumentError(
          StrCat(named, ": \"", key, "\" is for DICOMweb; a \"dimse\" endpoint has none"));
    }
  }
  if (!entry["dimse"].is_string()) {
    return absl::InvalidArgumentError(StrCat(named, ": \"dimse\" must be a string AET@HOST:PORT"));
  }
  Result<DimseAddress> address = ParseDimseAddress(entry["dimse"].get<std::string>());
  if (!address.ok()) {
    return absl::InvalidArgumentError(StrCat(named, ": \"dimse\": ", address.status().message()));
  }
  endpoint->dimse_ae_title = address->ae_title;
  endpoint->dimse_host = address->host;
  endpoint->dimse_port = address->port;
  if (entry.contains("calling_aet")) {
    if (!entry["calling_aet"].is_string() ||
        !CheckAeTitle(entry["calling_aet"].get<std::string>()).ok()) {
      return absl::InvalidArgumentError(
          StrCat(named, ": \"calling_aet\" must be an AE title (1-16 printable characters)"));
    }
    endpoint->calling_ae_title = entry["calling_aet"].get<std::string>();
  }
  return ParseRetrieveKeys(entry, named, endpoint);
}

Result<std::string> ReadSecret(const std::filesystem::path& path, const std::string& where) {
  std::ifstream file(path, std::ios::binary);
  if (!file) return absl::InvalidArgumentError(StrCat(where, ": cannot read ", path.string()));
  std::stringstream text;
  text << file.rdbuf();
  std::string secret = text.str();
  const auto space = [](unsigned char c) { return std::isspace(c) != 0; };
  while (!secret.empty() && space(secret.back())) secret.pop_back();
  secret.erase(secret.begin(), std::find_if_not(secret.begin(), secret.end(), space));
  if (secret.empty())
    return absl::InvalidArgumentError(StrCat(where, ": ", path.string(), " is empty"));
  if (secret.find_first_of("\r\n") != std::string::npos) {
    return absl::InvalidArgumentError(
        StrCat(where, ": ", path.string(), " holds more than one line"));
  }
  return secret;
}

Result<std::string> StringKey(const json& entry, const char* key, const std::string& where) {
  if (!entry.contains(key)) return std::string();
  if (!entry[key].is_string())
    return absl::InvalidArgumentError(StrCat(where, ": \"", key, "\" must be a string"));
  return entry[key].get<std::string>();
}

Status CheckUrl(const std::string& url, const std::string& where) {
  const bool http = url.starts_with("http://"), https = url.starts_with("https://");
  if (!http && !https) {
    return absl::InvalidArgumentError(
        StrCat(where, ": \"dicomweb\" must start with http:// or https://"));
  }
  const std::string rest = url.substr(http ? 7 : 8);
  const std::string authority = rest.substr(0, rest.find('/'));
  if (authority.empty())
    return absl::InvalidArgumentError(StrCat(where, ": \"dicomweb\" has no host"));
  if (authority.find('@') != std::string::npos) {
    return absl::InvalidArgumentError(
        StrCat(where, ": \"dicomweb\" must not hold credentials; use username and password_file"));
  }
  if (url.find_first_of("?# \t\r\n") != std::string::npos) {
    return absl::InvalidArgumentError(
        StrCat(where, ": \"dicomweb\" must be a plain base URL (no query, no spaces)"));
  }
  return absl::OkStatus();
}

Status ParseUsers(const json& entry, const std::string& named, PacsEndpoint* endpoint) {
  if (!entry.contains("users") || !entry["users"].is_array() || entry["users"].empty()) {
    return absl::InvalidArgumentError(StrCat(named,
                                             ": \"users\" must list the vpm users who may use it "
                                             "(or [\"*\"] for every signed-in user)"));
  }
  for (const json& user : entry["users"]) {
    if (!user.is_string() || user.get<std::string>().empty()) {
      return absl::InvalidArgumentError(StrCat(named, ": \"users\" must hold non-empty strings"));
    }
    endpoint->users.push_back(user.get<std::string>());
  }
  return absl::OkStatus();
}

// A "dicomweb" endpoint's keys: the URL, its credentials (a username and
// password_file, or a bearer_token_file; files relative to `folder`), a CA
// and the page size.
Status ParseDicomwebKeys(const json& entry, const std::filesystem::path& folder,
                         const std::string& named, PacsEndpoint* endpoint) {
  ASSIGN_OR_RETURN(endpoint->dicomweb_url, StringKey(entry, "dicomweb", named));
  if (endpoint->dicomweb_url.empty())
    return absl::InvalidArgumentError(StrCat(named, ": \"dicomweb\" is required"));
  RETURN_IF_ERROR(CheckUrl(endpoint->dicomweb_url, named));
  while (endpoint->dicomweb_url.ends_with('/')) endpoint->dicomweb_url.pop_back();
  ASSIGN_OR_RETURN(endpoint->username, StringKey(entry, "username", named));
  ASSIGN_OR_RETURN(const std::string password_file, StringKey(entry, "password_file", named));
  ASSIGN_OR_RETURN(const std::string token_file, StringKey(entry, "bearer_token_file", named));
  ASSIGN_OR_RETURN(const std::string ca_file, StringKey(entry, "ca_file", named));
  if (!password_file.empty() && !token_file.empty()) {
    return absl::InvalidArgumentError(
        StrCat(named, ": give password_file or bearer_token_file, not both"));
  }
  if (!password_file.empty() && endpoint->username.empty()) {
    return absl::InvalidArgumentError(StrCat(named, ": password_file needs a username"));
  }
  if (!endpoint->username.empty() && password_file.empty()) {
    return absl::InvalidArgumentError(StrCat(named, ": username needs a password_file"));
  }
  const auto resolve = [&](const std::string& name) {
    const std::filesystem::path p(name);
    return p.is_absolute() ? p : folder / p;
  };
  if (!password_file.empty()) {
    ASSIGN_OR_RETURN(endpoint->password,
                     ReadSecret(resolve(password_file), StrCat(named, ": password_file")));
  }
  if (!token_file.empty()) {
    ASSIGN_OR_RETURN(endpoint->bearer_token,
                     ReadSecret(resolve(token_file), StrCat(named, ": bearer_token_file")));
  }
  if (!ca_file.empty()) {
    endpoint->ca_file = resolve(ca_file).string();
    std::ifstream ca(endpoint->ca_file);
    if (!ca)
      return absl::InvalidArgumentError(
          StrCat(named, ": ca_file: cannot read ", endpoint->ca_file));
  }
  if (entry.contains("page_size")) {
    const json& page = entry["page_size"];
    if (!page.is_number_integer() || page.get<int64_t>() < 1 || page.get<int64_t>() > 1000) {
      return absl::InvalidArgumentError(
          StrCat(named, ": \"page_size\" must be an integer 1..1000"));
    }
    endpoint->page_size = page.get<int64_t>();
  }
  return absl::OkStatus();
}

Result<PacsEndpoint> ParseEntry(const json& entry, const std::filesystem::path& folder,
                                const std::string& where) {
  if (!entry.is_object()) return absl::InvalidArgumentError(StrCat(where, ": not an object"));
  for (const auto& [key, value] : entry.items()) {
    if (!kKeys.contains(key)) {
      return absl::InvalidArgumentError(StrCat(where, ": unknown key \"", key.substr(0, 40), "\""));
    }
  }
  PacsEndpoint endpoint;
  ASSIGN_OR_RETURN(endpoint.name, StringKey(entry, "name", where));
  if (Status name = CheckEndpointName(endpoint.name); !name.ok()) {
    return absl::InvalidArgumentError(StrCat(where, ": \"name\": ", name.message()));
  }
  const std::string named = StrCat(where, " (", endpoint.name, ")");
  if (entry.contains("receive")) {
    RETURN_IF_ERROR(ParseReceiveKeys(entry, named, &endpoint));
    return endpoint;
  }
  if (entry.contains("dimse") == entry.contains("dicomweb")) {
    return absl::InvalidArgumentError(StrCat(
        named, ": give \"dicomweb\" (a URL), \"dimse\" (AET@HOST:PORT) or \"receive\": true, "
               "one of them"));
  }
  if (entry.contains("retrieve") || entry.contains("move_destination") || entry.contains("from")) {
    if (!entry.contains("dimse") || entry.contains("from")) {
      return absl::InvalidArgumentError(StrCat(
          named, ": \"retrieve\" and \"move_destination\" are for \"dimse\", \"from\" for "
                 "\"receive\""));
    }
  }
  if (entry.contains("dimse")) {
    RETURN_IF_ERROR(ParseDimseKeys(entry, named, &endpoint));
    RETURN_IF_ERROR(ParseUsers(entry, named, &endpoint));
    return endpoint;
  }
  RETURN_IF_ERROR(ParseDicomwebKeys(entry, folder, named, &endpoint));
  RETURN_IF_ERROR(ParseUsers(entry, named, &endpoint));
  return endpoint;
}

}  // namespace

std::string EndpointLabel(const PacsEndpoint& endpoint) {
  return StrCat("PACS '", endpoint.name, "'");
}

bool PacsEndpoint::AllowsUser(std::string_view user) const {
  if (user.empty()) return false;
  return std::any_of(users.begin(), users.end(),
                     [&](const std::string& u) { return u == "*" || u == user; });
}

Status CheckEndpointName(std::string_view name) {
  const bool ok = !name.empty() && name.size() <= 64 && name.front() != '.' &&
                  std::all_of(name.begin(), name.end(), [](unsigned char c) {
                    return std::isalnum(c) || c == '.' || c == '_' || c == '-';
                  });
  if (ok) return absl::OkStatus();
  return absl::InvalidArgumentError(
      "an endpoint name is 1 to 64 of letters, digits, '.', '_' and '-', not starting with '.'");
}

Result<std::vector<PacsEndpoint>> ParsePacsEndpoints(std::string_view text,
                                                     const std::filesystem::path& folder,
                                                     std::string_view file_label) {
  const json parsed = json::parse(text, nullptr, /*allow_exceptions=*/false);
  if (parsed.is_discarded())
    return absl::InvalidArgumentError(StrCat(file_label, ": not valid JSON"));
  if (!parsed.is_array() || parsed.empty()) {
    return absl::InvalidArgumentError(StrCat(file_label, ": expected a JSON list of endpoints"));
  }
  std::vector<PacsEndpoint> endpoints;
  std::set<std::string> names;
  for (size_t i = 0; i < parsed.size(); ++i) {
    ASSIGN_OR_RETURN(PacsEndpoint endpoint,
                     ParseEntry(parsed[i], folder, StrCat(file_label, ": endpoint ", i + 1)));
    if (!names.insert(endpoint.name).second) {
      return absl::InvalidArgumentError(
          StrCat(file_label, ": endpoint name '", endpoint.name, "' given twice"));
    }
    endpoints.push_back(std::move(endpoint));
  }
  return endpoints;
}

Result<std::vector<PacsEndpoint>> ReadPacsEndpoints(const std::filesystem::path& path) {
  std::ifstream file(path, std::ios::binary);
  if (!file) return absl::InvalidArgumentError(StrCat("--pacs ", path.string(), ": cannot read"));
  std::stringstream text;
  text << file.rdbuf();
  return ParsePacsEndpoints(text.str(), path.parent_path(), StrCat("--pacs ", path.string()));
}

}  // namespace vpm::pacs
