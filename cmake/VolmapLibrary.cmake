# volmap_library(<name> [DEPENDS <volmap libraries>...] [EXTERNAL <imported targets>...])
#
# One static library per folder: every .cc under the calling folder
# (recursively) is a source, the library is `volmap_<name>` with the alias
# `volmap::<name>`, and headers are included from the repository root
# ("core/model/error_model.h"), in the build tree and once installed
# (<prefix>/include/volmap/...). The warning and sanitizer flags of
# volmap_options are the build's own and do not reach consumers.
include_guard(GLOBAL)
include(GNUInstallDirs)
include(VolmapPch)

set_property(GLOBAL PROPERTY VOLMAP_LIBRARIES "")

function(volmap_library name)
  cmake_parse_arguments(PARSE_ARGV 1 arg "" "" "DEPENDS;EXTERNAL")
  file(GLOB_RECURSE sources CONFIGURE_DEPENDS ${CMAKE_CURRENT_SOURCE_DIR}/*.cc)
  set(target volmap_${name})
  add_library(${target} STATIC ${sources})
  add_library(volmap::${name} ALIAS ${target})
  set_target_properties(${target} PROPERTIES EXPORT_NAME ${name} OUTPUT_NAME volmap_${name})
  target_include_directories(${target} PUBLIC
    $<BUILD_INTERFACE:${PROJECT_SOURCE_DIR}>
    $<INSTALL_INTERFACE:${CMAKE_INSTALL_INCLUDEDIR}/volmap>)
  target_link_libraries(${target} PRIVATE $<BUILD_INTERFACE:volmap_options>)
  foreach(dep IN LISTS arg_DEPENDS)
    target_link_libraries(${target} PUBLIC volmap_${dep})
  endforeach()
  target_link_libraries(${target} PUBLIC ${arg_EXTERNAL})
  volmap_use_pch(${target})
  set_property(GLOBAL APPEND PROPERTY VOLMAP_LIBRARIES ${target})
endfunction()
