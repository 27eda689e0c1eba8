# vpm_volume_io: file readers (NIfTI, NRRD, MetaImage, DICOM series, raw),
# the NIfTI writer and the source dispatcher ReadVolume.

# nifti_clib: Debian ships headers in /usr/include/nifti and the NIfTI-2
# capable library as libnifti2 (libniftiio is the NIfTI-1-only one).
find_path(NIFTI_INCLUDE_DIR nifti2_io.h PATH_SUFFIXES nifti REQUIRED)
find_library(NIFTI2_LIBRARY NAMES nifti2 REQUIRED)
find_library(ZNZ_LIBRARY NAMES znz REQUIRED)

add_library(vpm_volume_io
  ${CMAKE_CURRENT_LIST_DIR}/check_dicom_structure.cc
  ${CMAKE_CURRENT_LIST_DIR}/gzip_stream.cc
  ${CMAKE_CURRENT_LIST_DIR}/header_text.cc
  ${CMAKE_CURRENT_LIST_DIR}/metaimage_header.cc
  ${CMAKE_CURRENT_LIST_DIR}/nifti_geometry.cc
  ${CMAKE_CURRENT_LIST_DIR}/nifti_header.cc
  ${CMAKE_CURRENT_LIST_DIR}/nrrd_header.cc
  ${CMAKE_CURRENT_LIST_DIR}/parse_raw_source.cc
  ${CMAKE_CURRENT_LIST_DIR}/read_dicom_series.cc
  ${CMAKE_CURRENT_LIST_DIR}/read_dicom_slice.cc
  ${CMAKE_CURRENT_LIST_DIR}/read_file_bytes.cc
  ${CMAKE_CURRENT_LIST_DIR}/read_metaimage.cc
  ${CMAKE_CURRENT_LIST_DIR}/read_nifti.cc
  ${CMAKE_CURRENT_LIST_DIR}/read_nrrd.cc
  ${CMAKE_CURRENT_LIST_DIR}/read_raw.cc
  ${CMAKE_CURRENT_LIST_DIR}/read_volume.cc
  ${CMAKE_CURRENT_LIST_DIR}/voxel_type.cc
  ${CMAKE_CURRENT_LIST_DIR}/write_nifti.cc
)
# Third-party headers are system headers: their warnings are not ours.
target_include_directories(vpm_volume_io SYSTEM PRIVATE ${NIFTI_INCLUDE_DIR})
# DCMTK: dcmdata parses, dcmjpeg / dcmjpls (and dcmdata's RLE codec) decode
# compressed pixel data. Imported targets when DCMTK's config provides them,
# else the plain library list.
if(TARGET DCMTK::dcmdata)
  set(VPM_DCMTK_LIBS DCMTK::dcmdata DCMTK::dcmjpeg DCMTK::dcmjpls)
else()
  set(VPM_DCMTK_LIBS ${DCMTK_LIBRARIES})
  target_include_directories(vpm_volume_io SYSTEM PRIVATE ${DCMTK_INCLUDE_DIRS})
endif()
target_link_libraries(vpm_volume_io
  PUBLIC vpm_volume vpm_phantom absl::status absl::statusor absl::strings
  PRIVATE ${NIFTI2_LIBRARY} ${ZNZ_LIBRARY} ${VPM_DCMTK_LIBS} ZLIB::ZLIB m)
