#include "server/io/dicom_text.h"

#include <string_view>

#include <dcmtk/config/osconfig.h>  // must come first among DCMTK headers
#include <dcmtk/dcmdata/dcdatset.h>
#include <dcmtk/dcmdata/dcdeftag.h>
#include <dcmtk/dcmdata/dcspchrs.h>

#include "server/common/valid_utf8.h"

namespace vpm {

void ConvertDicomTextToUtf8(DcmDataset& ds) {
  OFString charset;
  if (ds.findAndGetOFStringArray(DCM_SpecificCharacterSet, charset).bad()) return;
  if (charset.empty() || charset == "ISO_IR 6" || charset == "ISO_IR 192") return;
  if (!DcmSpecificCharacterSet::isConversionAvailable()) return;
  if (ds.convertToUTF8().bad()) return;  // the text stays as stored
}

std::string DicomText(DcmItem& item, const DcmTagKey& tag) {
  OFString value;
  if (item.findAndGetOFStringArray(tag, value).bad()) return "";
  return ValidUtf8(std::string_view(value.c_str(), value.size()));
}

}  // namespace vpm
