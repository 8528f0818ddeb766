# Every third-party dependency is found here, once. scripts/install-deps.sh installs them.
find_package(Threads REQUIRED)
find_package(Eigen3 3.3 REQUIRED NO_MODULE)
find_package(OpenCV 4 REQUIRED COMPONENTS core imgproc imgcodecs features2d calib3d dnn)
find_package(Ceres 2 REQUIRED)
find_package(nlohmann_json 3 REQUIRED)
find_package(CLI11 REQUIRED)
find_package(spdlog REQUIRED)
find_package(fmt REQUIRED)
find_package(yaml-cpp REQUIRED)
find_package(TBB REQUIRED)
find_package(nanoflann REQUIRED)
find_package(Boost 1.74 REQUIRED)

# OpenCV ships variables, not targets: wrap them so that its headers count as system headers.
add_library(semslam_opencv INTERFACE)
target_include_directories(semslam_opencv SYSTEM INTERFACE ${OpenCV_INCLUDE_DIRS})
target_link_libraries(semslam_opencv INTERFACE ${OpenCV_LIBS})

# GeographicLib has a find module in a non-standard place and no target.
list(APPEND CMAKE_MODULE_PATH /usr/share/cmake/geographiclib)
find_package(GeographicLib REQUIRED)
add_library(semslam_geographiclib INTERFACE)
target_include_directories(semslam_geographiclib SYSTEM INTERFACE ${GeographicLib_INCLUDE_DIRS})
target_link_libraries(semslam_geographiclib INTERFACE ${GeographicLib_LIBRARIES})

# yaml-cpp 0.7 exports a plain target name.
add_library(semslam_yaml INTERFACE)
target_link_libraries(semslam_yaml INTERFACE yaml-cpp)

if(SEMSLAM_BUILD_TESTS)
  find_package(GTest REQUIRED)
endif()
if(SEMSLAM_BUILD_BENCH)
  find_package(benchmark REQUIRED)
endif()
