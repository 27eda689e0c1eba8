// Where the parts of a WADO-RS answer go: each part written to its own file
// in a folder as its bytes arrive (000001.dcm, 000002.dcm, ...), checked to
// be a DICOM Part 10 file, and held to a byte budget. The callbacks of a
// MultipartParser.
#pragma once

#include <cstdint>
#include <filesystem>
#include <fstream>
#include <string>
#include <string_view>

#include "server/common/status.h"
#include "server/pacs/multipart_parser.h"

namespace vpm::pacs {

class DicomPartWriter {
 public:
  // `folder` exists; `what` names the series in errors ("PACS 'x': series
  // UID"); at most `max_bytes` of parts in all.
  DicomPartWriter(std::filesystem::path folder, std::string what, int64_t max_bytes);

  // A part's Content-Type, when given, must be application/dicom (or
  // application/octet-stream): InvalidArgument otherwise. Internal when
  // the file cannot be made.
  Status Begin(const MultipartParser::Headers& headers);
  // ResourceExhausted past max_bytes; Internal when a write fails.
  Status Data(std::string_view chunk);
  // InvalidArgument unless the part holds "DICM" at byte 128.
  Status End();

  // The parser's callbacks, bound to this writer (which must outlive them).
  MultipartParser::Callbacks Callbacks();

  int64_t files() const { return files_; }  // parts completed and checked
  int64_t bytes() const { return bytes_; }  // bytes of every part

 private:
  const std::filesystem::path folder_;
  const std::string what_;
  const int64_t max_bytes_;
  std::ofstream file_;
  bool open_ = false;
  std::string head_;  // the part's first 132 bytes: preamble and "DICM"
  int64_t part_bytes_ = 0;
  int64_t files_ = 0;
  int64_t bytes_ = 0;
};

}  // namespace vpm::pacs
