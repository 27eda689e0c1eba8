// DICOM text as UTF-8: what files and PACS answers hold in their declared
// SpecificCharacterSet (or, undeclared, nearly always Latin-1) made fit for a
// protobuf string, a JSON document and a terminal.
#pragma once

#include <string>

class DcmDataset;
class DcmItem;
class DcmTagKey;

namespace vpm {

// Converts the dataset's text from its SpecificCharacterSet to UTF-8
// (DCMTK's convertToUTF8, through iconv): a Latin-1 "M\xfcller" or a
// Japanese name reads right wherever it is shown. Nothing to do without a
// declared set, for ISO_IR 6 (ASCII) and ISO_IR 192 (UTF-8); a set DCMTK
// cannot convert leaves the text as stored.
void ConvertDicomTextToUtf8(DcmDataset& ds);

// The value of `tag` in `item` as text (every value, backslash-separated),
// valid UTF-8 (ValidUtf8: stray bytes read as Latin-1); "" when absent.
std::string DicomText(DcmItem& item, const DcmTagKey& tag);

}  // namespace vpm
