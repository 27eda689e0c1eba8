// The JPEG 2000 codestream of each frame of encapsulated DICOM pixel data
// (PS3.5 A.4): a frame may span several fragments, but no fragment holds
// parts of two frames.
//
// Which fragments make a frame:
//   - one frame: all fragments, joined;
//   - as many fragments as frames: one each;
//   - else, with a Basic Offset Table (item 0, one little-endian uint32 a
//     frame: the byte offset of the frame's first fragment item from the
//     first fragment item's tag, item headers of 8 bytes counted): the
//     fragments from each offset to the next;
//   - else: a frame starts at a fragment that begins with a codestream's
//     SOC and SIZ markers (FF4F FF51) when the frame before it is complete,
//     i.e. ends with the EOC marker (FFD9; a pad byte 00 after it allowed).
// Anything else (offsets that do not fall on fragment starts, a count of
// codestreams other than `frames`) is InvalidArgument, naming what was found.
#pragma once

#include <cstdint>
#include <span>
#include <vector>

#include "server/common/status.h"

namespace vpm {

Result<std::vector<std::vector<uint8_t>>> Jpeg2000FrameCodestreams(
    std::span<const uint8_t> offset_table, const std::vector<std::span<const uint8_t>>& fragments,
    int64_t frames);

}  // namespace vpm
