# What a semslam binary says about itself (`semslam --version`, run.json, the Python module): the version, the
# git commit it was built from and the build type. The header is regenerated at every build but rewritten only
# when its text changes, so a new commit (or a tree that becomes dirty) recompiles just the files including it.
# A source tree without git (a release tarball) says "unknown".

set(SEMSLAM_BUILD_INFO_HEADER ${PROJECT_BINARY_DIR}/generated/semslam_build_info.h)
add_custom_target(semslam_build_info_header
  COMMAND ${CMAKE_COMMAND}
          -DSOURCE_DIR=${PROJECT_SOURCE_DIR}
          -DOUTPUT=${SEMSLAM_BUILD_INFO_HEADER}
          -DVERSION=${PROJECT_VERSION}
          -DBUILD_TYPE=${CMAKE_BUILD_TYPE}
          "-DCOMPILER=${CMAKE_CXX_COMPILER_ID} ${CMAKE_CXX_COMPILER_VERSION}"
          -P ${CMAKE_CURRENT_LIST_DIR}/SemslamWriteBuildInfo.cmake
  BYPRODUCTS ${SEMSLAM_BUILD_INFO_HEADER}
  COMMENT "semslam build info"
  VERBATIM)

# Include "semslam_build_info.h" (namespace semslam::build_info) through this target.
add_library(semslam_build_info INTERFACE)
target_include_directories(semslam_build_info INTERFACE ${PROJECT_BINARY_DIR}/generated)
add_dependencies(semslam_build_info semslam_build_info_header)
