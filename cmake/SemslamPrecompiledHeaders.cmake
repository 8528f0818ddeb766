# Precompiled headers for the heaviest third-party includes (Eigen, OpenCV's core, fmt, spdlog, nlohmann/json,
# GoogleTest), which a translation unit otherwise spends about half its compile time parsing.
#
# A precompiled header is only valid for a compilation with the same flags and predefined macros (GCC ignores an
# invalid one, clang refuses it), so one is built per kind of target and reused by every target of that kind:
#   module         the static libraries of src/semslam (position-independent);
#   fuzzed_module  those of them that carry libFuzzer's coverage instrumentation (semslam_fuzz_coverage);
#   program        the CLI, the benchmarks and the fuzz targets;
#   test           the test executables (with GoogleTest and semslam_test_code_options).
# Macros a target adds that none of these headers reads (its own SEMSLAM_* paths, Ceres' glog settings) leave
# the header valid. CMake compiles with GCC's -Winvalid-pch, so a header that stopped matching is a warning (an
# error with SEMSLAM_WERROR), not a silently slower build.
option(SEMSLAM_PRECOMPILED_HEADERS "Precompile the heaviest third-party headers" ON)

set(semslam_pch_headers
  <algorithm> <array> <cmath> <cstdint> <filesystem> <fstream> <functional> <map> <memory> <optional> <set>
  <sstream> <string> <string_view> <unordered_map> <vector>
  <Eigen/Core> <Eigen/Geometry> <opencv2/core.hpp> <opencv2/imgproc.hpp> <fmt/format.h> <spdlog/spdlog.h>
  <nlohmann/json.hpp>)
set(semslam_pch_test_headers ${semslam_pch_headers} <gtest/gtest.h> <gmock/gmock.h>)

# The target that owns the header of KIND, created on first use: an object library of one empty source whose
# flags are those of the targets that reuse its header.
function(semslam_pch_owner kind out_var)
  set(owner semslam_pch_${kind})
  if(NOT TARGET ${owner})
    set(stub ${PROJECT_BINARY_DIR}/pch/${kind}.cc)
    if(NOT EXISTS ${stub})
      file(WRITE ${stub} "// The translation unit that builds the precompiled header of semslam's ${kind} targets.\n")
    endif()
    add_library(${owner} OBJECT ${stub})
    target_link_libraries(${owner} PRIVATE semslam_options Eigen3::Eigen semslam_opencv fmt::fmt spdlog::spdlog
                                           nlohmann_json::nlohmann_json)
    set(headers ${semslam_pch_headers})
    if(kind STREQUAL "module" OR kind STREQUAL "fuzzed_module")
      set_target_properties(${owner} PROPERTIES POSITION_INDEPENDENT_CODE ON)
    endif()
    if(kind STREQUAL "fuzzed_module")
      target_link_libraries(${owner} PRIVATE semslam_fuzz_coverage)
    endif()
    if(kind STREQUAL "test")
      target_link_libraries(${owner} PRIVATE GTest::gtest GTest::gmock semslam_test_code_options)
      set(headers ${semslam_pch_test_headers})
    endif()
    target_precompile_headers(${owner} PRIVATE ${headers})
  endif()
  set(${out_var} ${owner} PARENT_SCOPE)
endfunction()

# semslam_precompiled_headers(TARGET KIND): TARGET compiles with the precompiled header of KIND (see above).
function(semslam_precompiled_headers target kind)
  if(NOT SEMSLAM_PRECOMPILED_HEADERS)
    return()
  endif()
  semslam_pch_owner(${kind} owner)
  target_precompile_headers(${target} REUSE_FROM ${owner})
endfunction()
