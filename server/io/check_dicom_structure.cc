#include "server/io/check_dicom_structure.h"

#include <cstdio>
#include <cstring>
#include <optional>
#include <string_view>

#include <dcmtk/config/osconfig.h>  // must come first among DCMTK headers
#include <dcmtk/dcmdata/dctag.h>
#include <dcmtk/dcmdata/dcvr.h>
#include <dcmtk/dcmdata/dcxfer.h>

#include "server/io/byte_order.h"

namespace vpm {
namespace {

constexpr uint32_t kUndefinedLength = 0xFFFFFFFFu;
constexpr uint16_t kItemGroup = 0xFFFE;
constexpr uint16_t kItem = 0xE000;
constexpr uint16_t kItemDelimiter = 0xE00D;
constexpr uint16_t kSequenceDelimiter = 0xE0DD;
constexpr size_t kMetaStart = 132;  // after the 128-byte preamble and "DICM"

struct Encoding {
  bool explicit_vr = true;
  Endian endian = Endian::kLittle;
};

struct Header {
  uint16_t group = 0;
  uint16_t element = 0;
  char vr[3] = {0, 0, 0};  // "" for item tags and implicit VR
  uint32_t length = 0;
  size_t value_start = 0;
};

// VRs as DCMTK classifies them, so that both agree on every length field.
bool IsStandardVr(const char* vr) {
  const DcmVR dcm_vr(vr);
  return dcm_vr.getEVR() != EVR_UNKNOWN && dcm_vr.isStandard();
}

bool HasLongLength(const char* vr) { return DcmVR(vr).usesExtendedLengthEncoding(); }

std::string TagName(uint16_t group, uint16_t element) {
  char buffer[16];
  std::snprintf(buffer, sizeof(buffer), "(%04X,%04X)", group, element);
  return buffer;
}

class Walker {
 public:
  explicit Walker(std::span<const uint8_t> bytes) : bytes_(bytes) {}

  Result<Header> ReadHeader(size_t pos, size_t end, const Encoding& enc) const;
  // Elements in [pos, end). With `in_item` an Item Delimitation ends them
  // early; *stop is the position after the last byte used.
  Status WalkElements(size_t pos, size_t end, const Encoding& enc, int depth, bool in_item,
                      size_t* stop);
  // The items of a sequence (or the fragments of encapsulated pixel data,
  // whose content is not parsed) in [pos, end); an undefined-length one ends
  // at its Sequence Delimitation.
  Status WalkItems(size_t pos, size_t end, const Encoding& enc, int depth, bool undefined_length,
                   bool parse_content, size_t* stop);
  std::string transfer_syntax;

 private:
  Status WalkValue(const Header& h, size_t end, const Encoding& enc, int depth, size_t* next);

  std::span<const uint8_t> bytes_;
  int64_t elements_ = 0;
};

Result<Header> Walker::ReadHeader(size_t pos, size_t end, const Encoding& enc) const {
  if (end - pos < 8) {
    return absl::InvalidArgumentError(
        StrCat("element header at byte ", pos, " is cut off (truncated)"));
  }
  const uint8_t* p = bytes_.data() + pos;
  Header h;
  h.group = LoadScalar<uint16_t>(p, enc.endian);
  h.element = LoadScalar<uint16_t>(p + 2, enc.endian);
  if (h.group == kItemGroup || !enc.explicit_vr) {
    h.length = LoadScalar<uint32_t>(p + 4, enc.endian);
    h.value_start = pos + 8;
  } else {
    std::memcpy(h.vr, p + 4, 2);
    if (!IsStandardVr(h.vr)) {
      return absl::InvalidArgumentError(
          StrCat("element ", TagName(h.group, h.element), " has an invalid VR"));
    }
    if (HasLongLength(h.vr)) {
      if (end - pos < 12)
        return absl::InvalidArgumentError("element header is cut off (truncated)");
      h.length = LoadScalar<uint32_t>(p + 8, enc.endian);
      h.value_start = pos + 12;
    } else {
      h.length = LoadScalar<uint16_t>(p + 6, enc.endian);
      h.value_start = pos + 8;
    }
  }
  if (h.length != kUndefinedLength && h.length > end - h.value_start) {
    return absl::InvalidArgumentError(StrCat(
        "element ", TagName(h.group, h.element), " at byte ", pos, " claims ", h.length,
        " bytes but only ", end - h.value_start, " follow (truncated or corrupt)"));
  }
  return h;
}

Status Walker::WalkValue(const Header& h, size_t end, const Encoding& enc, int depth,
                         size_t* next) {
  const std::string_view vr(h.vr);
  const bool pixel_data = h.group == 0x7FE0 && h.element == 0x0010;
  // Implicit VR: the data dictionary says which tags are sequences.
  const bool sequence =
      vr == "SQ" || (!enc.explicit_vr && DcmTag(h.group, h.element).getEVR() == EVR_SQ);
  // DCMTK decides by the VR whether (7FE0,0010) is pixel data or a sequence;
  // only the standard's VRs are accepted, so that it cannot be both.
  if (pixel_data && enc.explicit_vr && vr != "OB" && vr != "OW") {
    return absl::InvalidArgumentError(StrCat("PixelData has VR ", h.vr, ", not OB or OW"));
  }
  if (h.length != kUndefinedLength) {
    *next = h.value_start + h.length;
    if (!sequence) return absl::OkStatus();
    return WalkItems(h.value_start, *next, enc, depth + 1, false, true, next);
  }
  if (pixel_data) return WalkItems(h.value_start, end, enc, depth + 1, true, false, next);
  if (sequence || !enc.explicit_vr) {
    return WalkItems(h.value_start, end, enc, depth + 1, true, true, next);
  }
  if (vr == "UN") {  // an undefined-length UN holds implicit little-endian items
    return WalkItems(h.value_start, end, Encoding{false, Endian::kLittle}, depth + 1, true, true,
                     next);
  }
  return absl::InvalidArgumentError(StrCat("element ", TagName(h.group, h.element),
                                                 " has an undefined length but is not a sequence"));
}

Status Walker::WalkElements(size_t pos, size_t end, const Encoding& enc, int depth, bool in_item,
                            size_t* stop) {
  if (depth > kMaxDicomNesting) {
    return absl::InvalidArgumentError(
        StrCat("sequences nest deeper than ", kMaxDicomNesting, " levels"));
  }
  while (pos < end) {
    if (++elements_ > kMaxDicomElements) {
      return absl::InvalidArgumentError(
          StrCat("file holds more than ", kMaxDicomElements, " elements"));
    }
    ASSIGN_OR_RETURN(const Header h, ReadHeader(pos, end, enc));
    if (h.group == kItemGroup) {
      if (in_item && h.element == kItemDelimiter) {
        *stop = h.value_start;
        return absl::OkStatus();
      }
      return absl::InvalidArgumentError(
          StrCat("unexpected item tag ", TagName(h.group, h.element), " at byte ", pos));
    }
    RETURN_IF_ERROR(WalkValue(h, end, enc, depth, &pos));
  }
  if (in_item) return absl::InvalidArgumentError("item has no delimitation (truncated)");
  *stop = pos;
  return absl::OkStatus();
}

Status Walker::WalkItems(size_t pos, size_t end, const Encoding& enc, int depth,
                         bool undefined_length, bool parse_content, size_t* stop) {
  while (pos < end) {
    ASSIGN_OR_RETURN(const Header h, ReadHeader(pos, end, enc));
    if (h.group == kItemGroup && h.element == kSequenceDelimiter && undefined_length) {
      *stop = h.value_start;
      return absl::OkStatus();
    }
    if (h.group != kItemGroup || h.element != kItem) {
      return absl::InvalidArgumentError(
          StrCat("expected an item at byte ", pos, ", found ", TagName(h.group, h.element)));
    }
    if (++elements_ > kMaxDicomElements) {
      return absl::InvalidArgumentError(
          StrCat("file holds more than ", kMaxDicomElements, " elements"));
    }
    if (h.length == kUndefinedLength) {
      if (!parse_content)
        return absl::InvalidArgumentError("pixel data fragment of undefined length");
      RETURN_IF_ERROR(WalkElements(h.value_start, end, enc, depth, true, &pos));
    } else {
      pos = h.value_start + h.length;
      size_t ignored = 0;
      if (parse_content)
        RETURN_IF_ERROR(WalkElements(h.value_start, pos, enc, depth, false, &ignored));
    }
  }
  if (undefined_length)
    return absl::InvalidArgumentError("sequence has no delimitation (truncated)");
  *stop = pos;
  return absl::OkStatus();
}

// The encoding of the dataset after the file meta group. Only transfer
// syntaxes DCMTK knows are accepted: for an unknown one DCMTK guesses the
// encoding from the data, and its guess could differ from ours.
Result<Encoding> DatasetEncoding(const std::string& uid) {
  if (uid.empty()) return absl::InvalidArgumentError("file meta group has no TransferSyntaxUID");
  if (uid.size() > 64 || uid.find_first_not_of("0123456789.") != std::string::npos) {
    return absl::InvalidArgumentError("TransferSyntaxUID is not a UID (digits and dots)");
  }
  const DcmXfer xfer(uid.c_str());
  if (xfer.getXfer() == EXS_Unknown) {
    return absl::InvalidArgumentError(
        StrCat("unknown transfer syntax UID \"", uid.substr(0, 64), "\""));
  }
  if (xfer.getStreamCompression() != ESC_none) {
    return absl::UnimplementedError(
        StrCat("transfer syntax ", xfer.getXferName(), " (", uid, ") is not supported"));
  }
  return Encoding{static_cast<bool>(xfer.isExplicitVR()),
                  xfer.isBigEndian() ? Endian::kBig : Endian::kLittle};
}

// Walks the file meta group from kMetaStart; returns the position after it.
// The group always uses explicit VR little endian and ends where the group
// number changes. DCMTK instead trusts (0002,0000), the group length, when
// present; a file where the two disagree would be parsed differently by
// DCMTK than walked here, so it is refused (fuzz_dicom found such files
// making DCMTK misparse the dataset and allocate gigabytes).
Result<size_t> WalkMetaGroup(std::span<const uint8_t> bytes, Walker& walker) {
  const Encoding meta{true, Endian::kLittle};
  size_t pos = kMetaStart;
  std::optional<uint32_t> group_length;
  size_t after_group_length = pos;
  int32_t previous_element = -1;
  while (pos + 2 <= bytes.size() &&
         LoadScalar<uint16_t>(bytes.data() + pos, Endian::kLittle) == 2) {
    ASSIGN_OR_RETURN(const Header h, walker.ReadHeader(pos, bytes.size(), meta));
    // Ascending tags: no duplicates (which of two transfer syntaxes would
    // DCMTK use?), and a group length can only come first.
    if (h.element <= previous_element) {
      return absl::InvalidArgumentError(StrCat(
          "file meta element ", TagName(h.group, h.element), " is out of order or repeated"));
    }
    previous_element = h.element;
    if (h.length == kUndefinedLength) {
      return absl::InvalidArgumentError("file meta element has an undefined length");
    }
    if (h.element == 0x0000 && h.length != 4) {
      return absl::InvalidArgumentError("file meta group length (0002,0000) is not 4 bytes long");
    }
    if (h.element == 0x0000) {
      group_length = LoadScalar<uint32_t>(bytes.data() + h.value_start, Endian::kLittle);
      after_group_length = h.value_start + 4;
    }
    if (h.element == 0x0010) {
      if (std::string_view(h.vr) != "UI") {
        return absl::InvalidArgumentError("TransferSyntaxUID (0002,0010) is not a UI element");
      }
      walker.transfer_syntax.assign(reinterpret_cast<const char*>(bytes.data() + h.value_start),
                                    h.length);
    }
    pos = h.value_start + h.length;
  }
  // DCMTK also takes bytes 00 02 (group 0x0200 little endian) for a meta
  // tag; a dataset starting so would be read as meta by it, not by us.
  if (pos + 2 <= bytes.size() && bytes[pos] == 0x00 && bytes[pos + 1] == 0x02) {
    return absl::InvalidArgumentError("the end of the file meta group is ambiguous");
  }
  if (group_length.has_value() && *group_length != pos - after_group_length) {
    return absl::InvalidArgumentError(StrCat("file meta group length (0002,0000) says ",
                                                   *group_length, " bytes but the group holds ",
                                                   pos - after_group_length));
  }
  return pos;
}

}  // namespace

Result<std::string> CheckDicomStructure(std::span<const uint8_t> bytes) {
  if (bytes.size() < kMetaStart || std::memcmp(bytes.data() + 128, "DICM", 4) != 0) {
    return absl::InvalidArgumentError("not a DICOM file (no \"DICM\" prefix at byte 128)");
  }
  Walker walker(bytes);
  ASSIGN_OR_RETURN(const size_t dataset_start, WalkMetaGroup(bytes, walker));
  std::string uid = walker.transfer_syntax;
  while (!uid.empty() && (uid.back() == '\0' || uid.back() == ' ')) uid.pop_back();
  ASSIGN_OR_RETURN(const Encoding encoding, DatasetEncoding(uid));
  size_t end = 0;
  RETURN_IF_ERROR(walker.WalkElements(dataset_start, bytes.size(), encoding, 0, false, &end));
  return uid;
}

}  // namespace vpm
