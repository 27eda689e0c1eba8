// Writes the seed corpora of the fuzz targets: a few small valid files per
// format. Usage: vpm_make_fuzz_corpus OUT_DIR (fuzz/corpus in the source
// tree); the output is committed, so this runs only when seeds change.
#include <zlib.h>

#include <cstdio>
#include <cstring>
#include <filesystem>
#include <fstream>
#include <string>
#include <vector>

#include "server/io/gzip_stream.h"
#include "server/io/nifti_c_api.h"
#include "server/io/write_nifti.h"
#include "tests/io/dicom_test_util.h"

namespace {

namespace fs = std::filesystem;

void Write(const fs::path& path, const std::vector<uint8_t>& bytes) {
  fs::create_directories(path.parent_path());
  std::ofstream out(path, std::ios::binary | std::ios::trunc);
  out.write(reinterpret_cast<const char*>(bytes.data()),
            static_cast<std::streamsize>(bytes.size()));
}

std::vector<uint8_t> Bytes(const std::string& text) { return {text.begin(), text.end()}; }

std::vector<uint8_t> Concat(std::vector<uint8_t> a, const std::vector<uint8_t>& b) {
  a.insert(a.end(), b.begin(), b.end());
  return a;
}

std::vector<uint8_t> Shorts(std::initializer_list<int16_t> values, bool big_endian = false) {
  std::vector<uint8_t> out;
  for (int16_t v : values) {
    const uint16_t u = static_cast<uint16_t>(v);
    const uint8_t lo = static_cast<uint8_t>(u & 0xff), hi = static_cast<uint8_t>(u >> 8);
    out.push_back(big_endian ? hi : lo);
    out.push_back(big_endian ? lo : hi);
  }
  return out;
}

vpm::Volume SmallVolume() {
  vpm::VolumeGeometry g;
  g.dims = {3, 2, 2};
  g.spacing_mm = {0.5, 1.0, 2.0};
  g.origin_mm = {-10, 5, 20};
  g.direction = glm::dmat3(glm::dvec3(0, 1, 0), glm::dvec3(-1, 0, 0), glm::dvec3(0, 0, 1));
  std::vector<float> values(12);
  for (int n = 0; n < 12; ++n) values[n] = static_cast<float>(n * 10 - 40);
  return *vpm::Volume::Create(g, values);
}

void NiftiSeeds(const fs::path& dir) {
  const std::vector<uint8_t> nii = *vpm::EncodeNifti(SmallVolume());
  Write(dir / "float_sform_qform.nii", nii);
  Write(dir / "float.nii.gz", *vpm::GzipCompress(nii));
  nifti_1_header h;
  std::memset(&h, 0, sizeof(h));
  h.sizeof_hdr = 348;
  h.dim[0] = 3;
  h.dim[1] = 2;
  h.dim[2] = 2;
  h.dim[3] = 1;
  h.datatype = DT_INT16;
  h.bitpix = 16;
  for (float& p : h.pixdim) p = 1.0f;
  h.pixdim[0] = -1.0f;
  h.vox_offset = 352;
  h.scl_slope = 2.0f;
  h.scl_inter = -1024.0f;
  h.qform_code = 1;
  h.quatern_d = 0.70710678f;
  std::memcpy(h.magic, "n+1\0", 4);
  std::vector<uint8_t> bytes(352, 0);
  std::memcpy(bytes.data(), &h, sizeof(h));
  Write(dir / "int16_qform_slope.nii", Concat(bytes, Shorts({0, 1, 2, -3})));
  nifti_2_header h2;
  std::memset(&h2, 0, sizeof(h2));
  h2.sizeof_hdr = 540;
  std::memcpy(h2.magic, "n+2\0\r\n\032\n", 8);
  h2.datatype = DT_UINT8;
  h2.bitpix = 8;
  h2.dim[0] = 3;
  h2.dim[1] = 2;
  h2.dim[2] = 1;
  h2.dim[3] = 1;
  for (double& p : h2.pixdim) p = 1.0;
  h2.vox_offset = 544;
  h2.sform_code = 1;
  h2.srow_x[0] = -1;
  h2.srow_y[1] = -1;
  h2.srow_z[2] = 2;
  std::vector<uint8_t> bytes2(544, 0);
  std::memcpy(bytes2.data(), &h2, sizeof(h2));
  Write(dir / "nifti2_uint8.nii", Concat(bytes2, {7, 9}));
}

void NrrdSeeds(const fs::path& dir) {
  Write(dir / "ras_raw.nrrd",
        Concat(Bytes("NRRD0004\n# comment\ntype: short\ndimension: 3\n"
                     "space: right-anterior-superior\nsizes: 2 2 1\n"
                     "space directions: (0,0.5,0) (-2,0,0) (0,0,3)\nspace origin: (10,20,30)\n"
                     "kinds: domain domain domain\nendian: little\nencoding: raw\nkey:=value\n\n"),
               Shorts({1, -2, 3, 400})));
  Write(dir / "lps_gzip_big.nrrd",
        Concat(Bytes("NRRD0005\ntype: int16\ndimension: 3\nspace: left-posterior-superior\n"
                     "sizes: 3 1 1\nspace directions: (1.5,0,0) (0,1.5,0) (0,0,2)\n"
                     "endian: big\nencoding: gzip\nbyte skip: 0\n\n"),
               *vpm::GzipCompress(Shorts({-1000, 0, 1000}, true))));
  Write(dir / "ascii_2d.nrrd",
        Bytes("NRRD0004\ntype: float\ndimension: 2\nsizes: 3 1\nspacings: 0.5 2\n"
              "encoding: ascii\n\n1.5 -2\n300\n"));
  Write(dir / "detached.nhdr",
        Bytes("NRRD0004\ntype: uchar\ndimension: 3\nsizes: 2 2 2\nencoding: raw\n"
              "data file: self.raw\nline skip: 1\nbyte skip: -1\n"));
}

std::vector<uint8_t> Zlib(const std::vector<uint8_t>& data) {
  uLongf size = compressBound(data.size());
  std::vector<uint8_t> out(size);
  compress(out.data(), &size, data.data(), data.size());
  out.resize(size);
  return out;
}

void MetaImageSeeds(const fs::path& dir) {
  const std::string common =
      "ObjectType = Image\nNDims = 3\nBinaryData = True\nDimSize = 2 2 1\nElementType = MET_SHORT\n"
      "ElementSpacing = 0.5 0.75 2\nOffset = -5 6.5 7\nTransformMatrix = 0 1 0 -1 0 0 0 0 1\n"
      "AnatomicalOrientation = RAI\n";
  Write(dir / "attached.mha",
        Concat(Bytes(common + "BinaryDataByteOrderMSB = False\nElementDataFile = LOCAL\n"),
               Shorts({-1024, 0, 50, 3000})));
  Write(dir / "compressed_big.mha",
        Concat(Bytes(common + "BinaryDataByteOrderMSB = True\nCompressedData = True\n"
                              "ElementDataFile = LOCAL\n"),
               Zlib(Shorts({1, 2, 3, -4}, true))));
  Write(dir / "detached.mhd", Bytes("NDims = 2\nDimSize = 3 1\nElementType = MET_UCHAR\n"
                                    "HeaderSize = -1\nElementDataFile = v.raw\n"));
}

void DicomSeeds(const fs::path& dir) {
  using vpm::testing::DicomSliceSpec;
  DicomSliceSpec s;
  s.rows = 2;
  s.columns = 3;
  s.slope = 2.0;
  s.position_mm = glm::dvec3(-10, 20, 5);
  fs::create_directories(dir);
  vpm::testing::WriteDicomSlice(dir / "explicit_le.dcm", s);
  s.transfer_syntax = EXS_LittleEndianImplicit;
  vpm::testing::WriteDicomSlice(dir / "implicit_le.dcm", s);
  s.transfer_syntax = EXS_BigEndianExplicit;
  vpm::testing::WriteDicomSlice(dir / "explicit_be.dcm", s);
  s.transfer_syntax = EXS_RLELossless;
  vpm::testing::WriteDicomSlice(dir / "rle.dcm", s);
  s.is_signed = false;
  s.bits_stored = 12;
  s.transfer_syntax = EXS_JPEGProcess14SV1;
  vpm::testing::WriteDicomSlice(dir / "jpeg_lossless.dcm", s);
  s.transfer_syntax = EXS_JPEGLSLossless;
  vpm::testing::WriteDicomSlice(dir / "jpeg_ls.dcm", s);
  DicomSliceSpec eight;
  eight.rows = 2;
  eight.columns = 2;
  eight.bits_allocated = 8;
  eight.bits_stored = 8;
  eight.is_signed = false;
  vpm::testing::WriteDicomSlice(dir / "uint8.dcm", eight);
  eight.transfer_syntax = EXS_JPEGProcess1;
  vpm::testing::WriteDicomSlice(dir / "jpeg_baseline.dcm", eight);
}

void RawSeeds(const fs::path& dir) {
  Write(dir / "int16_le", Concat(Bytes("raw:a.raw?dims=2,2,1&type=int16&spacing=0.5,0.5,1\n"),
                                 Shorts({1, -2, 3, -4})));
  Write(dir / "uint16_be_offset",
        Concat(Bytes("raw:b.raw?dims=2,1,1&type=uint16&spacing=1,1,1&endian=big&offset=2\n"),
               Concat({0xAA, 0xBB}, Shorts({100, 200}, true))));
  Write(dir / "float32",
        Concat(Bytes("raw:c?dims=1,1,1&type=float&spacing=1,2,3\n"), {0x00, 0x00, 0x80, 0x3f}));
}

}  // namespace

int main(int argc, char** argv) {
  if (argc != 2) {
    std::fprintf(stderr, "usage: %s OUT_DIR\n", argv[0]);
    return 2;
  }
  const fs::path out = argv[1];
  NiftiSeeds(out / "nifti");
  NrrdSeeds(out / "nrrd");
  MetaImageSeeds(out / "metaimage");
  DicomSeeds(out / "dicom");
  RawSeeds(out / "raw");
  return 0;
}
