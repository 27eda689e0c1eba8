# Built-in synthetic phantoms ("phantom:abdomen..."), see docs/PHANTOM.md.
add_library(vpm_phantom
  phantom.cc
  phantom_abdomen.cc
  phantom_abdomen_skeleton.cc
  phantom_abdomen_volume.cc
  phantom_noise.cc
  phantom_raster.cc
  phantom_shapes.cc
)
target_link_libraries(vpm_phantom PUBLIC vpm_volume Threads::Threads absl::strings)
