#include "client/view/key_bindings.h"

#include <algorithm>
#include <cctype>

namespace vpm::view {
namespace {

constexpr size_t kKeyColumn = 16;  // characters

bool SameKey(std::string_view a, std::string_view b) {
  return a.size() == b.size() && std::equal(a.begin(), a.end(), b.begin(), [](char x, char y) {
           return std::toupper(static_cast<unsigned char>(x)) ==
                  std::toupper(static_cast<unsigned char>(y));
         });
}

std::string Padded(std::string text) {
  if (text.size() < kKeyColumn) text.resize(kKeyColumn, ' ');
  else text += ' ';
  return text;
}

}  // namespace

std::span<const KeyBinding> KeyBindings() {
  static const std::vector<KeyBinding> kBindings = {
      {{"F1", "H"}, Action::kToggleHelp, "show or hide this help"},
      {{"F2"}, Action::kToggleCases,
       "cases: mine and those shared with me; Up/Down, Return opens, R renames, Delete x2"},
      {{"G"}, Action::kToggleGrabMode, "grab mode on/off: left drag pulls tissue"},
      {{"1"}, Action::kPresetSoftTissue, "DVR preset ct-soft-tissue"},
      {{"2"}, Action::kPresetBone, "DVR preset ct-bone"},
      {{"3"}, Action::kPresetVessels, "DVR preset ct-vessels"},
      {{"4"}, Action::kPresetMriT1, "DVR preset mri-t1"},
      {{"5"}, Action::kPresetSlicerAaa, "DVR preset Slicer CT-AAA"},
      {{"6"}, Action::kPresetSlicerBone, "DVR preset Slicer CT-Bone"},
      {{"7"}, Action::kPresetSlicerMuscle, "DVR preset Slicer CT-Muscle"},
      {{"8"}, Action::kPresetSlicerChest, "DVR preset Slicer CT-Chest-Contrast-Enhanced"},
      {{"9"}, Action::kPresetSlicerSoftTissue, "DVR preset Slicer CT-Soft-Tissue"},
      {{"0"}, Action::kPresetSlicerMr, "DVR preset Slicer MR-Default"},
      {{"U"}, Action::kToggleViewCut,
       "view cut on/off: cut away what lies in front of the grab (off with crop or clip)"},
      {{"I"}, Action::kCycleInteractiveQuality,
       "frames while moving: fast, balanced, sharp (in turn; shown in the status bar)"},
      {{"M"}, Action::kMip, "maximum intensity projection (MIP)"},
      {{"O"}, Action::kToggleOverlay, "proxy-mesh overlay on/off"},
      {{"L"}, Action::kToggleSlices, "slices on/off: 3D, axial, coronal, sagittal (2 x 2)"},
      {{"B"}, Action::kToggleCropMode, "crop box on/off: left drag on a face moves it"},
      {{"C"}, Action::kToggleClipPlane, "clip plane facing you through the centre on/off (all)"},
      {{"P"}, Action::kAddClipPlane, "add a clip plane facing you (the newest one moves)"},
      {{"PageUp"}, Action::kScrollForward,
       "slice under the cursor +1 pixel (Shift 5); on 3D: clip plane 1 mm deeper"},
      {{"PageDown"}, Action::kScrollBack, "slice under the cursor -1 pixel; on 3D: clip plane back"},
      {{"R"}, Action::kRefineHere, "refine the mesh at the cursor (new session)"},
      {{"V", "Home"}, Action::kResetView, "reset the view"},
      {{"K"}, Action::kPinHere, "pin: hold the tissue at the cursor still"},
      {{"X"}, Action::kResetDeformation, "back to rest (drops kept drags and pins)"},
      {{"Ctrl+Z"}, Action::kUndo, "undo the last grab, pin or reset (a server with cases)"},
      {{"Ctrl+Shift+Z"}, Action::kRedo, "redo what was undone"},
      {{"S", "F12"}, Action::kScreenshot, "save a screenshot (PNG)"},
      {{"Q", "Escape"}, Action::kQuit, "quit"},
  };
  return kBindings;
}

std::optional<Action> ActionForKey(std::string_view sdl_key_name) {
  for (const KeyBinding& b : KeyBindings()) {
    for (std::string_view key : b.keys) {
      if (SameKey(key, sdl_key_name)) return b.action;
    }
  }
  return std::nullopt;
}

std::string KeyNameWithModifiers(std::string_view sdl_key_name, bool ctrl, bool shift) {
  if (!ctrl) return std::string(sdl_key_name);
  return std::string(shift ? "Ctrl+Shift+" : "Ctrl+") + std::string(sdl_key_name);
}

std::span<const MouseBinding> MouseBindings() {
  static constexpr MouseBinding kBindings[] = {
      {"left drag", "orbit"},
      {"wheel", "zoom"},
      {"middle drag", "pan (right drag too)"},
      {"G, left press", "grab the point under the cursor"},
      {"G, left drag", "pull the grabbed point"},
      {"G, left release", "let go (hold Shift: keep the drag)"},
      {"wheel on a slice", "scroll it: up +1 pixel along its normal (Shift 5)"},
      {"G, left on a slice", "grab there and drag within the slice's plane"},
      {"B, left drag", "on a box face: move it; elsewhere orbit"},
      {"C, Shift+left drag", "move the newest clip plane (up: deeper)"},
  };
  return kBindings;
}

std::vector<std::string> HelpLines() {
  std::vector<std::string> lines = {"Mouse:"};
  for (const MouseBinding& m : MouseBindings()) {
    lines.push_back("  " + Padded(std::string(m.control)) + std::string(m.description));
  }
  lines.push_back("Keys:");
  for (const KeyBinding& b : KeyBindings()) {
    std::string keys;
    for (std::string_view key : b.keys) {
      if (!keys.empty()) keys += ", ";
      keys += key;
    }
    lines.push_back("  " + Padded(keys) + std::string(b.description));
  }
  return lines;
}

}  // namespace vpm::view
