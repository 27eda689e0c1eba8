#include "client/view/case_panel.h"

#include <algorithm>
#include <cctype>
#include <cstdio>

namespace vpm::view {
namespace {

constexpr size_t kMaxTitleBytes = 256;  // as the server's UpdateCase

bool Is(std::string_view a, std::string_view b) {
  return a.size() == b.size() && std::equal(a.begin(), a.end(), b.begin(), [](char x, char y) {
           return std::tolower(static_cast<unsigned char>(x)) ==
                  std::tolower(static_cast<unsigned char>(y));
         });
}

std::string Row(const v3::CaseInfo& c, bool chosen) {
  char displacement[32];
  std::snprintf(displacement, sizeof displacement, "%.2f mm", c.max_displacement_mm());
  // The id's end tells cases of the same title apart.
  const std::string& id = c.case_id();
  const std::string tail = id.size() > 6 ? id.substr(id.size() - 6) : id;
  return (chosen ? "> " : "  ") + c.title() + "  [#" + tail + ", " + c.owner() + ", " +
         std::to_string(c.events()) + " events, " + displacement +
         (c.session_id().empty() ? "" : ", open") + "]";
}

}  // namespace

void CasePanel::SetCases(std::vector<v3::CaseInfo> cases, const std::string& current_case_id) {
  const std::string was = chosen_ < cases_.size() ? cases_[chosen_].case_id() : current_case_id;
  cases_ = std::move(cases);
  error_.clear();
  chosen_ = 0;
  for (size_t i = 0; i < cases_.size(); ++i) {
    if (cases_[i].case_id() == was) chosen_ = i;
  }
  confirm_delete_ = false;
}

void CasePanel::SetError(std::string message) { error_ = std::move(message); }

CasePanelRequest CasePanel::OnKey(std::string_view key) {
  using Kind = CasePanelRequest::Kind;
  const bool any = chosen_ < cases_.size();
  const std::string id = any ? cases_[chosen_].case_id() : "";
  if (renaming_) {
    if (Is(key, "Escape")) renaming_ = false;
    if (Is(key, "Backspace") && !title_.empty()) title_.pop_back();
    if (Is(key, "Return") && any && !title_.empty()) {
      renaming_ = false;
      return {Kind::kRename, id, title_};
    }
    return {};
  }
  if (!Is(key, "Delete")) confirm_delete_ = false;
  if (Is(key, "F2") || Is(key, "Escape")) return {Kind::kClose, "", ""};
  if (Is(key, "Up") && chosen_ > 0) --chosen_;
  if (Is(key, "Down") && chosen_ + 1 < cases_.size()) ++chosen_;
  if (!any) return {};
  if (Is(key, "Return")) return {Kind::kOpen, id, ""};
  if (Is(key, "R")) {
    renaming_ = true;
    title_.clear();
  }
  if (Is(key, "Delete")) {
    if (confirm_delete_) {
      confirm_delete_ = false;
      return {Kind::kDelete, id, ""};
    }
    confirm_delete_ = true;
  }
  return {};
}

void CasePanel::OnText(std::string_view text) {
  if (!renaming_) return;
  for (char c : text) {
    if (static_cast<unsigned char>(c) >= 0x20 && title_.size() < kMaxTitleBytes) title_ += c;
  }
}

std::vector<std::string> CasePanel::Lines(size_t columns) const {
  std::vector<std::string> lines = {"Cases (F2: close)  Up/Down, Return: open, R: rename, "
                                    "Delete x2: delete"};
  if (!error_.empty()) lines.push_back(error_);
  if (cases_.empty() && error_.empty()) lines.push_back("  no cases yet");
  for (size_t i = 0; i < cases_.size(); ++i) lines.push_back(Row(cases_[i], i == chosen_));
  if (renaming_) lines.push_back("new title: " + title_ + "_  (Return: keep, Escape: drop)");
  if (confirm_delete_ && chosen_ < cases_.size()) {
    lines.push_back("press Delete again to delete \"" + cases_[chosen_].title() + "\"");
  }
  for (std::string& line : lines) {
    if (line.size() > columns) line.resize(columns);
  }
  return lines;
}

}  // namespace vpm::view
