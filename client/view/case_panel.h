// The cases panel of vpm-view (F2): my cases and those shared with me, as
// ListCases gives them. Up / Down choose; Return opens the chosen case (the
// viewer moves to its session); R renames it (type the new title, Return
// keeps it, Escape drops it); Delete asks, Delete again deletes; F2 or Escape
// closes the panel. Window-free: the app turns its requests into calls.
#pragma once

#include <string>
#include <string_view>
#include <vector>

#include "vpm/v3/vpm.pb.h"

namespace vpm::view {

struct CasePanelRequest {
  enum class Kind { kNone, kOpen, kRename, kDelete, kClose };
  Kind kind = Kind::kNone;
  std::string case_id;
  std::string title;  // kRename
};

class CasePanel {
 public:
  // A new list; the choice stays on the same case when it is still there,
  // else on `current_case_id` (the viewer's), else the first.
  void SetCases(std::vector<v3::CaseInfo> cases, const std::string& current_case_id);
  void SetError(std::string message);
  // Forgets the list (the panel is opened anew): the next SetCases chooses
  // the viewer's case.
  void Clear() { cases_.clear(); error_.clear(); chosen_ = 0; renaming_ = confirm_delete_ = false; }
  // An SDL key name ("Up", "Return", "Delete", "R", ...).
  CasePanelRequest OnKey(std::string_view key_name);
  // Typed text while renaming (SDL_TEXTINPUT).
  void OnText(std::string_view text);
  bool renaming() const { return renaming_; }
  // The panel's text, one line a row, at most `columns` characters wide.
  std::vector<std::string> Lines(size_t columns) const;

 private:
  std::vector<v3::CaseInfo> cases_;
  std::string error_;
  size_t chosen_ = 0;
  bool renaming_ = false;
  bool confirm_delete_ = false;
  std::string title_;  // the title being typed
};

}  // namespace vpm::view
