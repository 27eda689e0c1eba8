#include "client/cli/case_commands.h"

#include <cstdio>
#include <ctime>
#include <memory>
#include <string>

#include <google/protobuf/util/json_util.h>

#include "client/cli/server_flags.h"
#include "client/common/proto_json.h"
#include "server/common/read_text_file.h"
#include "server/common/write_file.h"

namespace vpm::cli {
namespace {

using nlohmann::json;

// Unix ms as local "YYYY-MM-DD HH:MM".
std::string When(int64_t unix_ms) {
  const std::time_t t = static_cast<std::time_t>(unix_ms / 1000);
  std::tm local{};
  localtime_r(&t, &local);
  char text[32];
  std::strftime(text, sizeof text, "%Y-%m-%d %H:%M", &local);
  return text;
}

// CaseInfo.view with the proto's field names, or null when none is kept.
json ViewJson(const v3::CaseInfo& c) {
  if (!c.has_view()) return json(nullptr);
  google::protobuf::util::JsonPrintOptions options;
  options.preserve_proto_field_names = true;
  std::string text;
  if (!google::protobuf::util::MessageToJsonString(c.view(), &text, options).ok()) {
    return json(nullptr);
  }
  return json::parse(text, nullptr, false);
}

// One line of what the kept view shows: "MIP, crop, 1 clip plane, 2 slices".
std::string ViewSummary(const v3::RenderSettings& v) {
  const std::string preset = v.preset().empty() ? "auto" : v.preset();
  std::string out = v.mode() == v3::RENDER_MODE_MIP ? "MIP"
                    : v.has_render_tf() ? "DVR, transfer function " + v.render_tf().name()
                                        : "DVR, preset " + preset;
  if (v.has_crop()) out += ", crop";
  if (v.clip_size() > 0) {
    out += ", " + std::to_string(v.clip_size());
    out += v.clip_size() == 1 ? " clip plane" : " clip planes";
  }
  if (v.view_cut()) out += ", view cut";
  if (v.slices_size() > 0) {
    out += ", " + std::to_string(v.slices_size()) + (v.slices_size() == 1 ? " slice" : " slices");
  }
  return out;
}

json CaseJson(const v3::CaseInfo& c) {
  return {{"case_id", c.case_id()},
          {"title", c.title()},
          {"notes", c.notes()},
          {"owner", c.owner()},
          {"shared_with", json(std::vector<std::string>(c.shared_with().begin(),
                                                        c.shared_with().end()))},
          {"source", c.source()},
          {"events", c.events()},
          {"undone", c.undone()},
          {"max_displacement_mm", c.max_displacement_mm()},
          {"created_unix_ms", c.created_unix_ms()},
          {"modified_unix_ms", c.modified_unix_ms()},
          {"session_id", c.session_id()},
          {"camera", c.has_camera() ? json{{"azimuth_deg", c.camera().azimuth_deg()},
                                            {"elevation_deg", c.camera().elevation_deg()},
                                            {"distance_mm", c.camera().distance_mm()}}
                                      : json(nullptr)},
          {"view", ViewJson(c)}};
}

void PrintCase(const v3::CaseInfo& c) {
  std::printf("case %s\n  title: %s\n  owner: %s\n", c.case_id().c_str(), c.title().c_str(),
              c.owner().c_str());
  std::string shares;
  for (const std::string& u : c.shared_with()) shares += (shares.empty() ? "" : ", ") + u;
  if (!shares.empty()) std::printf("  shared with: %s\n", shares.c_str());
  std::printf("  source: %s\n  events: %lld (%lld undone)\n  largest displacement: %.3f mm\n",
              c.source().c_str(), static_cast<long long>(c.events()),
              static_cast<long long>(c.undone()), c.max_displacement_mm());
  std::printf("  created: %s  modified: %s\n", When(c.created_unix_ms()).c_str(),
              When(c.modified_unix_ms()).c_str());
  std::printf("  session: %s\n", c.session_id().empty() ? "(not open)" : c.session_id().c_str());
  if (c.has_view()) std::printf("  view: %s\n", ViewSummary(c.view()).c_str());
  if (!c.notes().empty()) std::printf("  notes: %s\n", c.notes().c_str());
}

struct Args {
  std::string case_id, session_id, text, user, file;
  bool json = false, revoke = false;
};

Status List(const ServerConnection& s, const Args& a) {
  v3::ListCasesResponse response;
  RETURN_IF_ERROR(FromGrpc(s.stub().ListCases(s.Context().get(), {}, &response)));
  if (a.json) {
    json cases = json::array();
    for (const auto& c : response.cases()) cases.push_back(CaseJson(c));
    PrintJson({{"cases", cases}});
    return absl::OkStatus();
  }
  std::printf("%-42s %-10s %-16s %7s %9s  %s\n", "CASE", "OWNER", "MODIFIED", "EVENTS", "MAX MM",
              "TITLE");
  for (const auto& c : response.cases()) {
    std::printf("%-42s %-10s %-16s %7lld %9.3f  %s%s\n", c.case_id().c_str(), c.owner().c_str(),
                When(c.modified_unix_ms()).c_str(), static_cast<long long>(c.events()),
                c.max_displacement_mm(), c.title().c_str(),
                c.session_id().empty() ? "" : "  (open)");
  }
  std::printf("%d cases\n", response.cases_size());
  return absl::OkStatus();
}

Status Show(const ServerConnection& s, const Args& a) {
  v3::GetCaseRequest request;
  request.set_case_id(a.case_id);
  v3::CaseInfo info;
  RETURN_IF_ERROR(FromGrpc(s.stub().GetCase(s.Context().get(), request, &info)));
  if (a.json) {
    PrintJson(CaseJson(info));
  } else {
    PrintCase(info);
  }
  return absl::OkStatus();
}

Status Open(const ServerConnection& s, const Args& a) {
  v3::OpenCaseRequest request;
  request.set_case_id(a.case_id);
  v3::SessionInfo session;
  RETURN_IF_ERROR(FromGrpc(s.stub().OpenCase(s.Context().get(), request, &session)));
  if (a.json) {
    PrintJson({{"session_id", session.session_id()},
               {"case_id", session.case_id()},
               {"volume_id", session.volume_id()},
               {"mesh_id", session.mesh_id()}});
  } else {
    std::printf("%s\n", session.session_id().c_str());
  }
  return absl::OkStatus();
}

Status Update(const ServerConnection& s, const Args& a, bool notes) {
  v3::UpdateCaseRequest request;
  request.set_case_id(a.case_id);
  if (notes) {
    request.set_notes(a.text);
  } else {
    request.set_title(a.text);
  }
  v3::CaseInfo info;
  RETURN_IF_ERROR(FromGrpc(s.stub().UpdateCase(s.Context().get(), request, &info)));
  PrintCase(info);
  return absl::OkStatus();
}

Status Delete(const ServerConnection& s, const Args& a) {
  v3::DeleteCaseRequest request;
  request.set_case_id(a.case_id);
  v3::DeleteCaseResponse response;
  RETURN_IF_ERROR(FromGrpc(s.stub().DeleteCase(s.Context().get(), request, &response)));
  std::printf("deleted %s\n", a.case_id.c_str());
  return absl::OkStatus();
}

Status Share(const ServerConnection& s, const Args& a) {
  v3::ShareCaseRequest request;
  request.set_case_id(a.case_id);
  request.set_user(a.user);
  request.set_revoke(a.revoke);
  v3::CaseInfo info;
  RETURN_IF_ERROR(FromGrpc(s.stub().ShareCase(s.Context().get(), request, &info)));
  PrintCase(info);
  return absl::OkStatus();
}

Status UndoOrRedo(const ServerConnection& s, const Args& a, bool redo) {
  v3::UndoRequest request;
  request.set_session_id(a.session_id);
  request.set_redo(redo);
  v3::UndoResponse response;
  RETURN_IF_ERROR(FromGrpc(s.stub().Undo(s.Context().get(), request, &response)));
  if (!response.changed()) {
    std::printf("nothing to %s\n", redo ? "redo" : "undo");
  } else {
    std::printf("%s: %lld events in effect, %lld undone, largest displacement %.3f mm\n",
                redo ? "redone" : "undone", static_cast<long long>(response.events()),
                static_cast<long long>(response.undone()), response.max_displacement_mm());
  }
  return absl::OkStatus();
}

using Run = Status (*)(const ServerConnection&, const Args&);

// The archive as JSON (protobuf's mapping, field names as in vpm.proto).
Status Export(const ServerConnection& s, const Args& a) {
  v3::ExportCaseRequest request;
  request.set_case_id(a.case_id);
  v3::CaseArchive archive;
  RETURN_IF_ERROR(FromGrpc(s.stub().ExportCase(s.Context().get(), request, &archive)));
  google::protobuf::util::JsonPrintOptions options;
  options.add_whitespace = true;
  options.preserve_proto_field_names = true;
  std::string json;
  if (!google::protobuf::util::MessageToJsonString(archive, &json, options).ok()) {
    return absl::InternalError("the archive could not be written as JSON");
  }
  RETURN_IF_ERROR(WriteFile(a.file, json));
  std::printf("wrote %s (%d events, volume %s)\n", a.file.c_str(), archive.events_size(),
              archive.source().c_str());
  return absl::OkStatus();
}

Status Import(const ServerConnection& s, const Args& a) {
  ASSIGN_OR_RETURN(const std::string json, ReadTextFile(a.file, "case import"));
  v3::ImportCaseRequest request;
  if (const auto parsed = google::protobuf::util::JsonStringToMessage(json, request.mutable_archive());
      !parsed.ok()) {
    return absl::InvalidArgumentError(
        StrCat(a.file, ": not a vpm case archive (", std::string(parsed.message()), ")"));
  }
  v3::CaseInfo info;
  RETURN_IF_ERROR(FromGrpc(s.stub().ImportCase(s.Context().get(), request, &info)));
  PrintCase(info);
  return absl::OkStatus();
}

CLI::App* Command(CLI::App* parent, const char* name, const char* help,
                  const std::shared_ptr<Args>& args, const ServerFlags* flags, int* exit_code,
                  std::function<Status(const ServerConnection&, const Args&)> run) {
  CLI::App* c = parent->add_subcommand(name, help);
  c->callback(WithServer(flags, exit_code,
                         [args, run](const ServerConnection& s) { return run(s, *args); }));
  return c;
}

}  // namespace

void AddCaseCommands(CLI::App& app, const ServerFlags* flags, int* exit_code) {
  CLI::App* cases =
      app.add_subcommand("case", "server: cases (a server started with --state-dir)");
  cases->require_subcommand(1);
  auto a = std::make_shared<Args>();
  Command(cases, "list", "my cases and those shared with me, newest first", a, flags, exit_code,
          List)
      ->add_flag("--json", a->json, "print JSON");
  CLI::App* show = Command(cases, "show", "one case: source, title, owner, shares, events, "
                                          "largest displacement", a, flags, exit_code, Show);
  show->add_option("case_id", a->case_id, "case id")->required();
  show->add_flag("--json", a->json, "print JSON");
  CLI::App* open = Command(cases, "open", "open the case (replayed if not open) and print its "
                                          "session id", a, flags, exit_code, Open);
  open->add_option("case_id", a->case_id, "case id")->required();
  open->add_flag("--json", a->json, "print JSON");
  CLI::App* rename = Command(cases, "rename", "set the case's title", a, flags, exit_code,
                             [](const ServerConnection& s, const Args& x) {
                               return Update(s, x, false);
                             });
  rename->add_option("case_id", a->case_id, "case id")->required();
  rename->add_option("title", a->text, "new title (at most 256 bytes)")->required();
  CLI::App* notes = Command(cases, "notes", "set the case's notes", a, flags, exit_code,
                            [](const ServerConnection& s, const Args& x) {
                              return Update(s, x, true);
                            });
  notes->add_option("case_id", a->case_id, "case id")->required();
  notes->add_option("text", a->text, "the notes")->required();
  CLI::App* del = Command(cases, "delete", "delete the case and everything stored of it", a,
                          flags, exit_code, Delete);
  del->add_option("case_id", a->case_id, "case id")->required();
  CLI::App* share = Command(cases, "share", "let a user read and watch the case", a, flags,
                            exit_code, Share);
  share->add_option("case_id", a->case_id, "case id")->required();
  share->add_option("--with", a->user, "user name")->required();
  share->add_flag("--revoke", a->revoke, "no longer share it with that user");
  CLI::App* undo = Command(cases, "undo", "take back the session's last action", a, flags,
                           exit_code, [](const ServerConnection& s, const Args& x) {
                             return UndoOrRedo(s, x, false);
                           });
  undo->add_option("session_id", a->session_id, "session id")->required();
  CLI::App* redo = Command(cases, "redo", "bring back the session's first undone action", a,
                           flags, exit_code, [](const ServerConnection& s, const Args& x) {
                             return UndoOrRedo(s, x, true);
                           });
  redo->add_option("session_id", a->session_id, "session id")->required();
  CLI::App* exp = Command(cases, "export", "write the case to a file (JSON) another server can "
                                           "import; its volume referenced by source", a, flags,
                          exit_code, Export);
  exp->add_option("case_id", a->case_id, "case id")->required();
  exp->add_option("file", a->file, "output file (.json)")->required();
  CLI::App* imp = Command(cases, "import", "a new case of mine from a file of case export", a,
                          flags, exit_code, Import);
  imp->add_option("file", a->file, "the file")->required();
}

}  // namespace vpm::cli
