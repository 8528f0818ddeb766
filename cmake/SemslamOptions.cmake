# Compile options shared by every semslam target (libraries, CLI, tests, benchmarks).
add_library(semslam_options INTERFACE)
target_compile_features(semslam_options INTERFACE cxx_std_20)
target_compile_options(semslam_options INTERFACE
  -Wall -Wextra -Wpedantic $<$<CXX_COMPILER_ID:GNU>:-Wshadow=local> -Wnon-virtual-dtor -Wcast-align
  -Woverloaded-virtual -Wimplicit-fallthrough -Wno-missing-field-initializers)
# Eigen's fixed-size vectorization needs aligned allocation; C++17 aligned new covers it.
target_compile_definitions(semslam_options INTERFACE EIGEN_MPL2_ONLY)
if(SEMSLAM_WERROR)
  target_compile_options(semslam_options INTERFACE -Werror)
endif()
if(SEMSLAM_NATIVE)
  # AVX2/FMA/POPCNT (x86-64-v3) where the build machine has them. Not -march=native: GCC 12 warns
  # spuriously inside its AVX-512 intrinsics when Eigen uses them.
  file(READ /proc/cpuinfo cpuinfo LIMIT 65536)
  if(cpuinfo MATCHES " avx2 " AND cpuinfo MATCHES " fma " AND cpuinfo MATCHES " bmi2 ")
    target_compile_options(semslam_options INTERFACE -march=x86-64-v3)
  endif()
endif()
if(SEMSLAM_SANITIZE)
  target_compile_options(semslam_options INTERFACE -fsanitize=address,undefined -fno-omit-frame-pointer
                                                   -fno-sanitize-recover=undefined)
  target_link_options(semslam_options INTERFACE -fsanitize=address,undefined)
endif()
if(SEMSLAM_THREAD_SANITIZER)
  target_compile_options(semslam_options INTERFACE -fsanitize=thread -fno-omit-frame-pointer)
  target_compile_definitions(semslam_options INTERFACE SEMSLAM_THREAD_SANITIZER_BUILD)
  target_link_options(semslam_options INTERFACE -fsanitize=thread)
endif()
# The modules that read user input (and the map loader) carry libFuzzer's coverage instrumentation; the rest
# of the library stays as fast as in the sanitizer build without it.
set(semslam_fuzzed_modules core io geo landmarks map semantics system)
add_library(semslam_fuzz_coverage INTERFACE)
target_compile_options(semslam_fuzz_coverage INTERFACE -fsanitize=fuzzer-no-link)
# Under a sanitizer the tests' own code is compiled without optimization: it is a third of the build and,
# instrumented at -O1, a test file took 54 s to compile against 24 s at -O0 (the library they test keeps -O1).
add_library(semslam_test_code_options INTERFACE)
if(SEMSLAM_SANITIZE OR SEMSLAM_THREAD_SANITIZER)
  target_compile_options(semslam_test_code_options INTERFACE -O0)
endif()

# semslam_module(NAME SOURCES... DEPS...) declares one library per folder: semslam_<NAME>.
function(semslam_module name)
  cmake_parse_arguments(ARG "" "" "SOURCES;DEPS" ${ARGN})
  add_library(semslam_${name} STATIC ${ARG_SOURCES})
  add_library(semslam::${name} ALIAS semslam_${name})
  target_include_directories(semslam_${name} PUBLIC ${PROJECT_SOURCE_DIR}/src)
  target_link_libraries(semslam_${name} PUBLIC ${ARG_DEPS} PRIVATE semslam_options)
  set_target_properties(semslam_${name} PROPERTIES POSITION_INDEPENDENT_CODE ON)
  if(SEMSLAM_FUZZ AND name IN_LIST semslam_fuzzed_modules)
    target_link_libraries(semslam_${name} PRIVATE semslam_fuzz_coverage)
    semslam_precompiled_headers(semslam_${name} fuzzed_module)
  else()
    semslam_precompiled_headers(semslam_${name} module)
  endif()
endfunction()
