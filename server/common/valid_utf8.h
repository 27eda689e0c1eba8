// Text from files and peers made valid UTF-8 before it reaches a protobuf
// string (a proto3 string must be UTF-8: the C++ parser refuses a message
// that holds anything else, so one Latin-1 byte in a note or a patient name
// fails the whole call) or a JSON document.
#pragma once

#include <string>
#include <string_view>

namespace vpm {

// `text` where it is valid UTF-8; else every byte that does not start a
// valid sequence (a lone continuation byte, a truncated or overlong
// sequence, a surrogate, a code point over U+10FFFF) is read as Latin-1 and
// written as the character it names there (0xE4 -> "ä", U+00E4): DICOM
// files and answers that declare no character set but hold accented names
// are nearly always ISO 8859-1. Valid sequences are kept as they are.
std::string ValidUtf8(std::string_view text);

// True when `text` is valid UTF-8 (the same rules).
bool IsValidUtf8(std::string_view text);

// True when every byte of `text` is ASCII (under 0x80).
bool IsAscii(std::string_view text);

}  // namespace vpm
