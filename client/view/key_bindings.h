// The viewer's mouse and key controls: one table, from which the key
// handling, `vpm-view --help` and the on-screen help overlay all read, so
// the three never disagree.
#pragma once

#include <optional>
#include <span>
#include <string>
#include <string_view>
#include <vector>

namespace vpm::view {

enum class Action {
  kToggleHelp,
  kToggleCases,
  kToggleGrabMode,
  kPresetSoftTissue,
  kPresetBone,
  kPresetVessels,
  kPresetMriT1,
  kPresetSlicerAaa,
  kPresetSlicerBone,
  kPresetSlicerMuscle,
  kPresetSlicerChest,
  kPresetSlicerSoftTissue,
  kPresetSlicerMr,
  kToggleViewCut,
  kCycleInteractiveQuality,
  kMip,
  kToggleOverlay,
  kToggleSlices,
  kToggleCropMode,
  kToggleClipPlane,
  kAddClipPlane,
  kScrollForward,
  kScrollBack,
  kRefineHere,
  kPinHere,
  kResetView,
  kResetDeformation,
  kUndo,
  kRedo,
  kScreenshot,
  kQuit,
};

struct KeyBinding {
  std::vector<std::string_view> keys;  // SDL key names (SDL_GetKeyName), e.g. "F1", "H"
  Action action;
  std::string_view description;
};

std::span<const KeyBinding> KeyBindings();
// The action of an SDL key name, if any ("h" and "H" are the same key);
// with Ctrl (or Cmd) held the name is "Ctrl+" or "Ctrl+Shift+" and the key's
// (KeyNameWithModifiers).
std::optional<Action> ActionForKey(std::string_view sdl_key_name);
// "Z" with Ctrl and Shift held: "Ctrl+Shift+Z"; without Ctrl (or Cmd): the
// key's name as it is.
std::string KeyNameWithModifiers(std::string_view sdl_key_name, bool ctrl, bool shift);
struct MouseBinding {
  std::string_view control;  // "left drag"; "G, ..." means in grab mode
  std::string_view description;
};
std::span<const MouseBinding> MouseBindings();
// The whole help text, mouse then keys, one control a line, keys padded
// into a column: used by --help and by the overlay.
std::vector<std::string> HelpLines();

}  // namespace vpm::view
