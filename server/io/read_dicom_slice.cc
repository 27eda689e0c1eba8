#include "server/io/read_dicom_slice.h"

#include <cmath>
#include <cstring>
#include <memory>
#include <mutex>
#include <optional>

#include <dcmtk/config/osconfig.h>  // must come first among DCMTK headers
#include <dcmtk/dcmdata/dcdeftag.h>
#include <dcmtk/dcmdata/dcfilefo.h>
#include <dcmtk/dcmdata/dcistrmb.h>
#include <dcmtk/dcmdata/dcpixel.h>
#include <dcmtk/dcmdata/dcpixseq.h>
#include <dcmtk/dcmdata/dcpxitem.h>
#include <dcmtk/dcmdata/dcrledrg.h>
#include <dcmtk/dcmdata/dcsequen.h>
#include <dcmtk/dcmdata/dcxfer.h>
#include <dcmtk/dcmjpeg/djdecode.h>
#include <dcmtk/dcmjpls/djdecode.h>

#include "server/common/prefix_status.h"
#include "server/io/check_dicom_structure.h"
#include "server/io/decode_jpeg2000.h"
#include "server/io/dicom_text.h"
#include "server/io/header_text.h"
#include "server/io/jpeg2000_frames.h"
#include "server/io/voxel_type.h"

namespace vpm {
namespace {

// DCMTK keeps its decoders in a process-wide registry; registering them once,
// on first use, is the library's intended pattern.
void RegisterDecodersOnce() {
  static std::once_flag once;
  std::call_once(once, [] {
    DcmRLEDecoderRegistration::registerCodecs();
    DJDecoderRegistration::registerCodecs();
    DJLSDecoderRegistration::registerCodecs();
  });
}

Result<std::unique_ptr<DcmFileFormat>> ParseFile(std::span<const uint8_t> bytes) {
  // Only structurally sound files reach DCMTK (see check_dicom_structure.h).
  ASSIGN_OR_RETURN(const std::string syntax_uid, CheckDicomStructure(bytes));
  DcmInputBufferStream stream;
  stream.setBuffer(bytes.data(), static_cast<offile_off_t>(bytes.size()));
  stream.setEos();
  auto file = std::make_unique<DcmFileFormat>();
  file->transferInit();
  // The syntax the walk used, so that DCMTK never guesses another.
  const OFCondition cond =
      file->read(stream, DcmXfer(syntax_uid.c_str()).getXfer(), EGL_noChange, DCM_MaxReadLength);
  file->transferEnd();
  if (cond.bad()) {
    return absl::InvalidArgumentError(
        StrCat("not a readable DICOM file (truncated or corrupt): ", cond.text()));
  }
  return file;
}

struct PixelFormat {
  int64_t bits_allocated = 0;
  int64_t bits_stored = 0;
  int64_t high_bit = 0;
  bool is_signed = false;
  double slope = 1.0;
  double intercept = 0.0;
};

Result<int64_t> GetInt(DcmItem& ds, const DcmTagKey& tag, const char* name,
                       std::optional<int64_t> fallback = std::nullopt) {
  Sint32 value = 0;
  if (ds.findAndGetSint32(tag, value).good()) return value;
  Uint16 value16 = 0;
  if (ds.findAndGetUint16(tag, value16).good()) return value16;
  if (fallback.has_value()) return *fallback;
  return absl::InvalidArgumentError(StrCat(name, " is missing"));
}

Result<double> GetDouble(DcmItem& ds, const DcmTagKey& tag, unsigned long pos, const char* name,
                         std::optional<double> fallback = std::nullopt) {
  Float64 value = 0.0;
  if (ds.findAndGetFloat64(tag, value, pos).good()) {
    if (!std::isfinite(value)) return absl::InvalidArgumentError(StrCat(name, " is not finite"));
    return value;
  }
  if (fallback.has_value()) return *fallback;
  return absl::InvalidArgumentError(
      StrCat(name, " is missing (needed to place the slice in space)"));
}

Status CheckImageKind(DcmDataset& ds) {
  ASSIGN_OR_RETURN(const int64_t samples, GetInt(ds, DCM_SamplesPerPixel, "SamplesPerPixel", 1));
  if (samples != 1) {
    return absl::UnimplementedError(
        StrCat("SamplesPerPixel is ", samples, "; only greyscale images are supported"));
  }
  OFString photometric;
  if (ds.findAndGetOFString(DCM_PhotometricInterpretation, photometric).good() &&
      photometric != "MONOCHROME1" && photometric != "MONOCHROME2") {
    return absl::UnimplementedError(
        StrCat("PhotometricInterpretation ", photometric.c_str(), " is not supported"));
  }
  return absl::OkStatus();
}

// NumberOfFrames (1 when absent). Several frames need per-frame positions
// (an enhanced CT/MR image's PerFrameFunctionalGroupsSequence, one item per
// frame); older multi-frame kinds (cine, NM) do not place their frames.
Result<int64_t> CountFrames(DcmDataset& ds) {
  ASSIGN_OR_RETURN(const int64_t frames, GetInt(ds, DCM_NumberOfFrames, "NumberOfFrames", 1));
  if (frames < 1) return absl::InvalidArgumentError(StrCat("NumberOfFrames is ", frames));
  if (frames == 1) return frames;
  DcmSequenceOfItems* per_frame = nullptr;
  if (ds.findAndGetSequence(DCM_PerFrameFunctionalGroupsSequence, per_frame).bad() ||
      per_frame == nullptr) {
    return absl::UnimplementedError(
        StrCat("multi-frame images (", frames,
               " frames) without PerFrameFunctionalGroupsSequence are not supported"));
  }
  if (static_cast<int64_t>(per_frame->card()) != frames) {
    return absl::InvalidArgumentError(StrCat("PerFrameFunctionalGroupsSequence has ",
                                             per_frame->card(), " items for ", frames, " frames"));
  }
  return frames;
}

Result<PixelFormat> ReadPixelFormat(DcmDataset& ds) {
  PixelFormat f;
  ASSIGN_OR_RETURN(f.bits_allocated, GetInt(ds, DCM_BitsAllocated, "BitsAllocated"));
  if (f.bits_allocated != 8 && f.bits_allocated != 16) {
    return absl::UnimplementedError(
        StrCat("BitsAllocated is ", f.bits_allocated, "; only 8 and 16 are supported"));
  }
  ASSIGN_OR_RETURN(f.bits_stored, GetInt(ds, DCM_BitsStored, "BitsStored", f.bits_allocated));
  ASSIGN_OR_RETURN(f.high_bit, GetInt(ds, DCM_HighBit, "HighBit", f.bits_stored - 1));
  if (f.bits_stored < 1 || f.bits_stored > f.bits_allocated || f.high_bit >= f.bits_allocated ||
      f.high_bit + 1 < f.bits_stored) {
    return absl::InvalidArgumentError(StrCat("BitsStored ", f.bits_stored, " / HighBit ",
                                             f.high_bit, " do not fit BitsAllocated ",
                                             f.bits_allocated));
  }
  ASSIGN_OR_RETURN(const int64_t representation,
                   GetInt(ds, DCM_PixelRepresentation, "PixelRepresentation", 0));
  f.is_signed = representation == 1;
  ASSIGN_OR_RETURN(f.slope, GetDouble(ds, DCM_RescaleSlope, 0, "RescaleSlope", 1.0));
  ASSIGN_OR_RETURN(f.intercept, GetDouble(ds, DCM_RescaleIntercept, 0, "RescaleIntercept", 0.0));
  if (f.slope == 0.0) return absl::InvalidArgumentError("RescaleSlope is 0");
  return f;
}

// Where one frame's attributes live: the item of a functional group macro
// (per-frame first, then shared), or the dataset itself for a classic image.
struct FrameItems {
  DcmItem* pixel_measures;   // PixelSpacing, SliceThickness
  DcmItem* orientation;      // ImageOrientationPatient
  DcmItem* position;         // ImagePositionPatient
  DcmItem* value_transform;  // RescaleSlope, RescaleIntercept
};

// A frame's functional groups (null where the image has none).
struct FrameGroups {
  DcmItem* per_frame = nullptr;
  DcmItem* shared = nullptr;

  // The first item of `sequence` in the per-frame group, else the shared
  // one; null when neither has it.
  DcmItem* Find(const DcmTagKey& sequence) const {
    DcmItem* item = nullptr;
    for (DcmItem* group : {per_frame, shared}) {
      if (group != nullptr && group->findAndGetSequenceItem(sequence, item, 0).good() &&
          item != nullptr) {
        return item;
      }
    }
    return nullptr;
  }
};

FrameGroups GroupsOfFrame(DcmDataset& ds, int64_t frame) {
  FrameGroups g;
  if (ds.findAndGetSequenceItem(DCM_SharedFunctionalGroupsSequence, g.shared, 0).bad()) {
    g.shared = nullptr;
  }
  if (ds.findAndGetSequenceItem(DCM_PerFrameFunctionalGroupsSequence, g.per_frame,
                                static_cast<signed long>(frame))
          .bad()) {
    g.per_frame = nullptr;
  }
  return g;
}

FrameItems ItemsOfFrame(DcmDataset& ds, int64_t frame) {
  const FrameGroups g = GroupsOfFrame(ds, frame);
  const auto find = [&](const DcmTagKey& sequence) {
    DcmItem* item = g.Find(sequence);
    return item != nullptr ? item : static_cast<DcmItem*>(&ds);
  };
  return {find(DCM_PixelMeasuresSequence), find(DCM_PlaneOrientationSequence),
          find(DCM_PlanePositionSequence), find(DCM_PixelValueTransformationSequence)};
}

Status ReadGeometry(const FrameItems& items, DicomSlice& slice) {
  for (int n = 0; n < 2; ++n) {
    ASSIGN_OR_RETURN(slice.pixel_spacing_mm[n],
                     GetDouble(*items.pixel_measures, DCM_PixelSpacing, n, "PixelSpacing"));
  }
  for (int n = 0; n < 6; ++n) {
    ASSIGN_OR_RETURN(
        slice.orientation[n],
        GetDouble(*items.orientation, DCM_ImageOrientationPatient, n, "ImageOrientationPatient"));
  }
  for (int n = 0; n < 3; ++n) {
    ASSIGN_OR_RETURN(slice.position_mm[n], GetDouble(*items.position, DCM_ImagePositionPatient, n,
                                                     "ImagePositionPatient"));
  }
  ASSIGN_OR_RETURN(slice.slice_thickness_mm,
                   GetDouble(*items.pixel_measures, DCM_SliceThickness, 0, "SliceThickness", 0.0));
  return absl::OkStatus();
}

// The frame's own rescale where its functional groups carry one.
Status ReadRescale(const FrameItems& items, PixelFormat& f) {
  ASSIGN_OR_RETURN(f.slope,
                   GetDouble(*items.value_transform, DCM_RescaleSlope, 0, "RescaleSlope", f.slope));
  ASSIGN_OR_RETURN(f.intercept, GetDouble(*items.value_transform, DCM_RescaleIntercept, 0,
                                          "RescaleIntercept", f.intercept));
  if (f.slope == 0.0) return absl::InvalidArgumentError("RescaleSlope is 0");
  return absl::OkStatus();
}

// Identity fields, and whether the image is one that never belongs in a
// volume: scanners put localizers (scouts) and screenshots beside the slices,
// sometimes under the same SeriesInstanceUID.
void ReadIdentity(DcmDataset& ds, DicomSlice& slice) {
  slice.series_uid = DicomText(ds, DCM_SeriesInstanceUID);
  slice.series_description = DicomText(ds, DCM_SeriesDescription);
  slice.modality = DicomText(ds, DCM_Modality);
  slice.sop_class_uid = DicomText(ds, DCM_SOPClassUID);
  Sint32 number = 0;
  if (ds.findAndGetSint32(DCM_SeriesNumber, number).good()) slice.series_number = number;
  slice.stack = {.echo_numbers = DicomText(ds, DCM_EchoNumbers),
                 .echo_time = DicomText(ds, DCM_EchoTime),
                 .temporal_position = DicomText(ds, DCM_TemporalPositionIdentifier),
                 .trigger_time = DicomText(ds, DCM_TriggerTime),
                 .diffusion_b_value = DicomText(ds, DCM_DiffusionBValue),
                 .image_type = DicomText(ds, DCM_ImageType),
                 .acquisition_number = DicomText(ds, DCM_AcquisitionNumber)};
  // Secondary Capture Image Storage and its multi-frame variants (1.2.840.10008.5.1.4.1.1.7.x).
  constexpr std::string_view kSecondaryCapture = "1.2.840.10008.5.1.4.1.1.7";
  const std::string_view sop = slice.sop_class_uid;
  if (sop == kSecondaryCapture || sop.starts_with(StrCat(kSecondaryCapture, "."))) {
    slice.not_a_slice_reason = "secondary capture";
  } else if (ToLowerAscii(DicomText(ds, DCM_ImageType)).find("localizer") != std::string::npos) {
    slice.not_a_slice_reason = "localizer";
  }
}

// An enhanced image's frame: where its functional groups carry a stack
// attribute, that value replaces the top level's (EffectiveEchoTime of
// MREchoSequence, TemporalPositionIndex and StackID of
// FrameContentSequence, DiffusionBValue of MRDiffusionSequence, FrameType of
// the MR / CT image frame type sequences).
void ReadFrameStack(DcmDataset& ds, int64_t frame, DicomStackAttributes& a) {
  struct Field {
    DcmTagKey sequence;
    DcmTagKey tag;
    std::string DicomStackAttributes::*value;
  };
  static const Field kFields[] = {
      {DCM_MREchoSequence, DCM_EffectiveEchoTime, &DicomStackAttributes::echo_time},
      {DCM_FrameContentSequence, DCM_TemporalPositionIndex,
       &DicomStackAttributes::temporal_position},
      {DCM_FrameContentSequence, DCM_StackID, &DicomStackAttributes::stack_id},
      {DCM_MRDiffusionSequence, DCM_DiffusionBValue, &DicomStackAttributes::diffusion_b_value},
      {DCM_MRImageFrameTypeSequence, DCM_FrameType, &DicomStackAttributes::image_type},
      {DCM_CTImageFrameTypeSequence, DCM_FrameType, &DicomStackAttributes::image_type},
  };
  const FrameGroups g = GroupsOfFrame(ds, frame);
  for (const Field& field : kFields) {
    DcmItem* item = g.Find(field.sequence);
    if (item == nullptr) continue;
    std::string value = DicomText(*item, field.tag);
    if (!value.empty()) a.*field.value = std::move(value);
  }
}

// DCMTK 3.6.7's JPEG decoder loops forever when the marker walk it does to
// find the frame header (DJCodecDecoder::scanJpegDataForBitDepth) meets a TEM
// marker (FF01), which it does not step over. The same walk is done here and
// such fragments are refused; everything else is left to the decoder.
Status CheckJpegMarkers(const Uint8* data, uint32_t length) {
  uint32_t offset = 0;
  while (data != nullptr && offset + 4 < length) {
    const uint8_t marker = data[offset + 1];
    if (data[offset] != 0xff) return absl::OkStatus();  // DCMTK stops here
    const bool frame_header =
        (marker >= 0xc0 && marker <= 0xcf && marker != 0xc4 && marker != 0xc8 && marker != 0xcc);
    if (frame_header) return absl::OkStatus();  // found: the walk ends
    if (marker == 0x01) {
      return absl::InvalidArgumentError("JPEG data holds a TEM marker before its frame header");
    }
    const uint32_t segment = (uint32_t{data[offset + 2]} << 8) | data[offset + 3];
    if (marker == 0xff) {
      offset += 1;
    } else if ((marker >= 0xd0 && marker <= 0xd9) || (marker > 0x02 && marker <= 0xbf)) {
      offset += 2;
    } else if (marker >= 0xc4) {
      offset += segment + 2;
    } else {
      return absl::OkStatus();  // an invalid marker: DCMTK stops too
    }
  }
  return absl::OkStatus();
}

Status CheckFragments(DcmDataset& ds, E_TransferSyntax xfer) {
  DcmElement* element = nullptr;
  if (ds.findAndGetElement(DCM_PixelData, element).bad() || element == nullptr ||
      element->ident() != EVR_PixelData) {
    return absl::InvalidArgumentError("PixelData is missing");
  }
  DcmPixelSequence* sequence = nullptr;
  if (static_cast<DcmPixelData*>(element)
          ->getEncapsulatedRepresentation(xfer, nullptr, sequence)
          .bad() ||
      sequence == nullptr) {
    return absl::InvalidArgumentError("compressed PixelData has no fragments");
  }
  for (unsigned long n = 0; n < sequence->card(); ++n) {
    DcmPixelItem* item = nullptr;
    Uint8* data = nullptr;
    if (sequence->getItem(item, n).good() && item != nullptr && item->getUint8Array(data).good()) {
      RETURN_IF_ERROR(CheckJpegMarkers(data, item->getLength()));
    }
  }
  return absl::OkStatus();
}

bool IsJpeg2000(E_TransferSyntax xfer) {
  return xfer == EXS_JPEG2000LosslessOnly || xfer == EXS_JPEG2000;
}

// The codestream of each frame (jpeg2000_frames.h: one fragment or several
// a frame, by the Basic Offset Table or by the codestreams' markers).
Result<std::vector<std::vector<uint8_t>>> Jpeg2000Codestreams(DcmDataset& ds, int64_t frames) {
  DcmElement* element = nullptr;
  DcmPixelSequence* sequence = nullptr;
  if (ds.findAndGetElement(DCM_PixelData, element).bad() || element == nullptr ||
      element->ident() != EVR_PixelData ||
      static_cast<DcmPixelData*>(element)
          ->getEncapsulatedRepresentation(ds.getOriginalXfer(), nullptr, sequence)
          .bad() ||
      sequence == nullptr || sequence->card() < 2) {
    return absl::InvalidArgumentError("JPEG 2000 PixelData has no fragments");
  }
  // Item 0: the Basic Offset Table (may be empty); then the fragments.
  std::vector<std::span<const uint8_t>> items;
  for (unsigned long n = 0; n < sequence->card(); ++n) {
    DcmPixelItem* item = nullptr;
    Uint8* data = nullptr;
    if (sequence->getItem(item, n).bad() || item == nullptr || item->getUint8Array(data).bad()) {
      return absl::InvalidArgumentError(StrCat("JPEG 2000 fragment ", n, " cannot be read"));
    }
    items.emplace_back(data, data == nullptr ? 0 : item->getLength());
  }
  const std::vector<std::span<const uint8_t>> fragments(items.begin() + 1, items.end());
  return Jpeg2000FrameCodestreams(items[0], fragments, frames);
}

// JPEG 2000 frames through OpenJPEG; decoded samples are the stored values.
Status ReadJpeg2000Frames(DcmDataset& ds, const std::vector<PixelFormat>& formats,
                          std::vector<DicomSlice>& slices) {
  const int64_t frames = static_cast<int64_t>(slices.size());
  ASSIGN_OR_RETURN(const std::vector<std::vector<uint8_t>> streams,
                   Jpeg2000Codestreams(ds, frames));
  for (int64_t f = 0; f < frames; ++f) {
    DicomSlice& slice = slices[f];
    ASSIGN_OR_RETURN(const std::vector<int32_t> samples,
                     DecodeJpeg2000(streams[f], slice.columns, slice.rows));
    slice.values.resize(samples.size());
    for (size_t n = 0; n < samples.size(); ++n) {
      slice.values[n] = DoubleToFloat(samples[n] * formats[f].slope + formats[f].intercept);
    }
  }
  return absl::OkStatus();
}

Status DecompressIfNeeded(DcmDataset& ds) {
  const DcmXfer xfer(ds.getOriginalXfer());
  if (!xfer.isEncapsulated()) return absl::OkStatus();
  if (xfer.getXfer() != EXS_RLELossless) RETURN_IF_ERROR(CheckFragments(ds, xfer.getXfer()));
  RegisterDecodersOnce();
  const OFCondition cond = ds.chooseRepresentation(EXS_LittleEndianExplicit, nullptr);
  if (cond.bad() || !ds.canWriteXfer(EXS_LittleEndianExplicit)) {
    return absl::UnimplementedError(StrCat(
        "transfer syntax ", xfer.getXferName(), " (", xfer.getXferID(),
        ") is compressed and could not be decoded: ", cond.bad() ? cond.text() : "no decoder"));
  }
  return absl::OkStatus();
}

// Stored sample -> value: keep bits [high_bit - bits_stored + 1, high_bit],
// sign-extend when signed, then rescale.
float SampleToValue(uint32_t raw, const PixelFormat& f) {
  const int64_t shift = f.high_bit + 1 - f.bits_stored;
  const uint32_t mask = f.bits_stored >= 32 ? 0xffffffffu : ((1u << f.bits_stored) - 1u);
  int64_t value = (raw >> shift) & mask;
  if (f.is_signed && (value >> (f.bits_stored - 1)) != 0) value -= int64_t{1} << f.bits_stored;
  return DoubleToFloat(static_cast<double>(value) * f.slope + f.intercept);
}

// Frame `frame` of the (decoded) pixel data; frames follow each other.
Status ReadPixels(DcmDataset& ds, const PixelFormat& f, int64_t frame, DicomSlice& slice) {
  const int64_t count = slice.rows * slice.columns;
  const int64_t first = frame * count;
  DcmElement* element = nullptr;
  if (ds.findAndGetElement(DCM_PixelData, element).bad() || element == nullptr) {
    return absl::InvalidArgumentError("PixelData is missing");
  }
  const int64_t have_bytes = element->getLength();
  const int64_t need_bytes = (first + count) * (f.bits_allocated / 8);
  if (have_bytes < need_bytes) {
    return absl::InvalidArgumentError(StrCat(
        "PixelData holds ", have_bytes, " bytes but ", frame + 1, " frames of ", slice.rows, "x",
        slice.columns, "x", f.bits_allocated, " bits need ", need_bytes, " (truncated)"));
  }
  slice.values.resize(static_cast<size_t>(count));
  if (f.bits_allocated == 8) {
    Uint8* data = nullptr;
    if (element->getUint8Array(data).bad() || data == nullptr) {
      return absl::InvalidArgumentError("PixelData cannot be read as 8-bit samples");
    }
    for (int64_t n = 0; n < count; ++n) slice.values[n] = SampleToValue(data[first + n], f);
  } else {
    Uint16* data = nullptr;
    if (element->getUint16Array(data).bad() || data == nullptr) {
      return absl::InvalidArgumentError("PixelData cannot be read as 16-bit samples");
    }
    for (int64_t n = 0; n < count; ++n) slice.values[n] = SampleToValue(data[first + n], f);
  }
  return absl::OkStatus();
}

}  // namespace

bool LooksLikeDicom(std::span<const uint8_t> bytes) {
  return bytes.size() >= 132 && std::memcmp(bytes.data() + 128, "DICM", 4) == 0;
}

Result<std::vector<DicomSlice>> ParseDicomFrames(std::span<const uint8_t> bytes,
                                                 const VolumeLimits& limits, DicomDecode decode) {
  ASSIGN_OR_RETURN(const std::unique_ptr<DcmFileFormat> file, ParseFile(bytes));
  DcmDataset& ds = *file->getDataset();
  DicomSlice base;
  if (!ds.tagExists(DCM_PixelData)) return std::vector<DicomSlice>{base};  // not an image
  ConvertDicomTextToUtf8(ds);
  base.is_image = true;
  ReadIdentity(ds, base);
  if (!base.not_a_slice_reason.empty()) return std::vector<DicomSlice>{base};
  RETURN_IF_ERROR(CheckImageKind(ds));
  ASSIGN_OR_RETURN(const int64_t frames, CountFrames(ds));
  ASSIGN_OR_RETURN(base.rows, GetInt(ds, DCM_Rows, "Rows"));
  ASSIGN_OR_RETURN(base.columns, GetInt(ds, DCM_Columns, "Columns"));
  VolumeGeometry planes;
  planes.dims = {base.columns, base.rows, frames};
  RETURN_IF_ERROR(ValidateGeometry(planes, limits));  // before any decoding
  ASSIGN_OR_RETURN(const PixelFormat format, ReadPixelFormat(ds));
  std::vector<DicomSlice> slices(static_cast<size_t>(frames), base);
  std::vector<PixelFormat> formats(static_cast<size_t>(frames), format);
  for (int64_t f = 0; f < frames; ++f) {
    const FrameItems items = ItemsOfFrame(ds, f);
    if (frames > 1) ReadFrameStack(ds, f, slices[f].stack);
    Status status = ReadGeometry(items, slices[f]);
    if (status.ok() && frames > 1) status = ReadRescale(items, formats[f]);
    if (!status.ok()) {
      return frames == 1 ? status : PrefixStatus(status, StrCat("frame ", f + 1));
    }
  }
  if (decode == DicomDecode::kHeaderOnly) return slices;
  if (IsJpeg2000(ds.getOriginalXfer())) {
    RETURN_IF_ERROR(ReadJpeg2000Frames(ds, formats, slices));
    return slices;
  }
  RETURN_IF_ERROR(DecompressIfNeeded(ds));
  for (int64_t f = 0; f < frames; ++f) RETURN_IF_ERROR(ReadPixels(ds, formats[f], f, slices[f]));
  return slices;
}

}  // namespace vpm
