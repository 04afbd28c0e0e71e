# `cmake --install`: the volmap binary (cli/CMakeLists.txt), every library of
# volmap_library() with its headers under <prefix>/include/volmap/, and a CMake
# package so that a consumer writes
#   find_package(volmap REQUIRED)
#   target_link_libraries(app PRIVATE volmap::postproc)
# (tests/consumer/ is such a project, built against an install in CI).
include(GNUInstallDirs)
include(CMakePackageConfigHelpers)

get_property(volmap_libraries GLOBAL PROPERTY VOLMAP_LIBRARIES)
install(TARGETS ${volmap_libraries} EXPORT volmapTargets
  ARCHIVE DESTINATION ${CMAKE_INSTALL_LIBDIR})
foreach(folder core maps gcode postproc)
  install(DIRECTORY ${PROJECT_SOURCE_DIR}/${folder}/
    DESTINATION ${CMAKE_INSTALL_INCLUDEDIR}/volmap/${folder}
    FILES_MATCHING PATTERN "*.h")
endforeach()

set(volmap_cmake_dir ${CMAKE_INSTALL_LIBDIR}/cmake/volmap)
install(EXPORT volmapTargets NAMESPACE volmap:: DESTINATION ${volmap_cmake_dir})
configure_package_config_file(${PROJECT_SOURCE_DIR}/cmake/volmapConfig.cmake.in
  ${PROJECT_BINARY_DIR}/volmapConfig.cmake INSTALL_DESTINATION ${volmap_cmake_dir})
write_basic_package_version_file(${PROJECT_BINARY_DIR}/volmapConfigVersion.cmake
  COMPATIBILITY SameMinorVersion)
install(FILES ${PROJECT_BINARY_DIR}/volmapConfig.cmake
  ${PROJECT_BINARY_DIR}/volmapConfigVersion.cmake DESTINATION ${volmap_cmake_dir})
