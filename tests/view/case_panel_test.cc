// vpm-view's cases panel without a window: choosing, opening, renaming,
// deleting only on the second press.
#include "client/view/case_panel.h"

#include <gtest/gtest.h>

namespace vpm::view {
namespace {

v3::CaseInfo Case(const std::string& id, const std::string& title) {
  v3::CaseInfo c;
  c.set_case_id(id);
  c.set_title(title);
  c.set_owner("alice");
  c.set_events(3);
  c.set_max_displacement_mm(4.25);
  return c;
}

TEST(CasePanel, ChoosesOpensRenamesAndDeletesOnlyWhenAskedTwice) {
  CasePanel panel;
  panel.SetCases({Case("case-a", "liver"), Case("case-b", "kidney")}, "case-b");
  std::vector<std::string> lines = panel.Lines(200);
  ASSERT_EQ(lines.size(), 3u);
  EXPECT_EQ(lines[2].rfind("> kidney", 0), 0u) << lines[2];  // the viewer's case chosen
  EXPECT_NE(lines[2].find("4.25 mm"), std::string::npos);
  panel.OnKey("Up");
  CasePanelRequest open = panel.OnKey("Return");
  EXPECT_EQ(open.kind, CasePanelRequest::Kind::kOpen);
  EXPECT_EQ(open.case_id, "case-a");

  EXPECT_EQ(panel.OnKey("R").kind, CasePanelRequest::Kind::kNone);
  ASSERT_TRUE(panel.renaming());
  EXPECT_EQ(panel.OnKey("Return").kind, CasePanelRequest::Kind::kNone);  // no title yet
  panel.OnText("liverr\x01");  // a control character is dropped
  panel.OnKey("Backspace");
  panel.OnText(", left lobe");
  CasePanelRequest rename = panel.OnKey("Return");
  EXPECT_EQ(rename.kind, CasePanelRequest::Kind::kRename);
  EXPECT_EQ(rename.title, "liver, left lobe");
  EXPECT_FALSE(panel.renaming());

  EXPECT_EQ(panel.OnKey("Delete").kind, CasePanelRequest::Kind::kNone);
  EXPECT_NE(panel.Lines(200).back().find("press Delete again"), std::string::npos);
  EXPECT_EQ(panel.OnKey("Down").kind, CasePanelRequest::Kind::kNone);  // another key: no delete
  EXPECT_EQ(panel.OnKey("Delete").kind, CasePanelRequest::Kind::kNone);
  CasePanelRequest remove = panel.OnKey("Delete");
  EXPECT_EQ(remove.kind, CasePanelRequest::Kind::kDelete);
  EXPECT_EQ(remove.case_id, "case-b");
  EXPECT_EQ(panel.OnKey("Escape").kind, CasePanelRequest::Kind::kClose);
  for (const std::string& line : panel.Lines(20)) EXPECT_LE(line.size(), 20u);
}

TEST(CasePanel, SaysWhyThereIsNoList) {
  CasePanel panel;
  panel.SetError("this server keeps no cases (start vpm-server with --state-dir DIR)");
  EXPECT_NE(panel.Lines(200)[1].find("--state-dir"), std::string::npos);
  EXPECT_EQ(panel.OnKey("Return").kind, CasePanelRequest::Kind::kNone);
}

}  // namespace
}  // namespace vpm::view
