# Precompiled headers (VOLMAP_PCH, on by default).
#
# Eigen, nlohmann/json, fmt and GoogleTest take about 6 s of parsing in every
# translation unit that includes them, more than most of volmap's own files
# take to compile; on CI's two cores that was most of each build. They are
# parsed once here, into two precompiled headers that every target reuses:
# volmap_pch for the libraries, the command line and the benchmarks,
# volmap_pch_tests (the same plus GoogleTest) for the tests. The headers are
# only third-party and standard ones, so a change in volmap never rebuilds
# them. Every source still includes what it uses: build with
# -DVOLMAP_PCH=OFF to check that (the installed-package test of .ci/run
# compiles the public headers without them).
include_guard(GLOBAL)

option(VOLMAP_PCH "Precompile the third-party headers (faster builds)" ON)

set(VOLMAP_PCH_HEADERS
  <algorithm> <array> <cmath> <cstdint> <filesystem> <fstream> <functional>
  <map> <memory> <optional> <random> <sstream> <stdexcept> <string>
  <string_view> <vector>
  <Eigen/Dense> <fmt/format.h> <nlohmann/json.hpp>)

# GCC 12 loses, for precompiled headers, the rule that its middle-end
# warnings inside system headers are not reported: libstdc++'s std::string
# code inlined into volmap then raises -Warray-bounds, -Wstringop-overflow
# and -Wstringop-overread false positives (the same files compile clean
# with the headers included as text). With GCC 12 and VOLMAP_PCH these are
# off; they stay on with -DVOLMAP_PCH=OFF and for every other compiler.
if(VOLMAP_PCH AND CMAKE_CXX_COMPILER_ID STREQUAL "GNU" AND CMAKE_CXX_COMPILER_VERSION VERSION_LESS 13)
  target_compile_options(volmap_options INTERFACE
    -Wno-array-bounds -Wno-stringop-overflow -Wno-stringop-overread)
endif()

# volmap_pch_host(<target> [<libraries>...]): an object library that only
# builds the precompiled header, with the flags of the targets that reuse it.
function(volmap_pch_host name)
  set(source ${CMAKE_CURRENT_BINARY_DIR}/${name}.cc)
  if(NOT EXISTS ${source})
    file(WRITE ${source} "// Hosts the precompiled header of cmake/VolmapPch.cmake.\n")
  endif()
  add_library(${name} OBJECT ${source})
  target_link_libraries(${name} PRIVATE volmap_options ${ARGN})
  target_include_directories(${name} PRIVATE ${PROJECT_SOURCE_DIR})
  target_precompile_headers(${name} PRIVATE ${VOLMAP_PCH_HEADERS})
endfunction()

# volmap_use_pch(<target> [TESTS]): <target> reuses the libraries' (or the
# tests') precompiled header.
function(volmap_use_pch target)
  if(NOT VOLMAP_PCH)
    return()
  endif()
  cmake_parse_arguments(PARSE_ARGV 1 arg "TESTS" "" "")
  set(host volmap_pch)
  if(arg_TESTS)
    set(host volmap_pch_tests)
    if(NOT TARGET ${host})
      find_package(GTest REQUIRED)
      volmap_pch_host(${host} Eigen3::Eigen nlohmann_json::nlohmann_json fmt::fmt GTest::gtest)
      target_precompile_headers(${host} PRIVATE <gtest/gtest.h>)
      target_compile_options(${host} PRIVATE ${VOLMAP_TEST_FLAGS})  # as the tests
    endif()
  elseif(NOT TARGET ${host})
    volmap_pch_host(${host} Eigen3::Eigen nlohmann_json::nlohmann_json fmt::fmt)
  endif()
  # The reusing target compiles with the header's include folders and
  # definitions (a test of the command line links no volmap library).
  target_link_libraries(${target} PRIVATE Eigen3::Eigen nlohmann_json::nlohmann_json fmt::fmt)
  target_precompile_headers(${target} REUSE_FROM ${host})
endfunction()
