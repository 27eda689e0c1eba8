# vpm_add_shaders(TARGET name SOURCES a.comp b.comp)
# Compiles each compute shader with glslangValidator into a C header holding
# the SPIR-V as `const uint32_t k<Name>Spv[]` (name from the file stem in
# CamelCase), with a depfile so edits to included .glsl files rebuild it.
# The headers land in ${CMAKE_BINARY_DIR}/shaders_gen/shaders/<stem>.spv.h and
# are included as "shaders/<stem>.spv.h". Nothing is read from disk at run time.
function(vpm_add_shaders)
  cmake_parse_arguments(ARG "" "TARGET" "SOURCES" ${ARGN})
  set(out_dir ${CMAKE_BINARY_DIR}/shaders_gen/shaders)
  file(MAKE_DIRECTORY ${out_dir})
  set(headers)
  foreach(src ${ARG_SOURCES})
    get_filename_component(stem ${src} NAME_WE)
    string(REPLACE "_" ";" parts ${stem})
    set(camel "")
    foreach(p ${parts})
      string(SUBSTRING ${p} 0 1 first)
      string(TOUPPER ${first} first)
      string(SUBSTRING ${p} 1 -1 rest)
      string(APPEND camel "${first}${rest}")
    endforeach()
    set(header ${out_dir}/${stem}.spv.h)
    add_custom_command(
      OUTPUT ${header}
      COMMAND ${GLSLANG_VALIDATOR} -V --target-env vulkan1.1 -Os
              --depfile ${header}.d --vn k${camel}Spv
              -o ${header} ${CMAKE_CURRENT_SOURCE_DIR}/${src}
      DEPENDS ${CMAKE_CURRENT_SOURCE_DIR}/${src}
      DEPFILE ${header}.d
      COMMENT "glslang ${src}"
      VERBATIM)
    list(APPEND headers ${header})
  endforeach()
  add_custom_target(${ARG_TARGET}_gen DEPENDS ${headers})
  add_library(${ARG_TARGET} INTERFACE)
  add_dependencies(${ARG_TARGET} ${ARG_TARGET}_gen)
  target_include_directories(${ARG_TARGET} INTERFACE ${CMAKE_BINARY_DIR}/shaders_gen)
endfunction()
