# concert_drill_perception (see ../CMakeLists.txt): blue blobs and ArUco markers (OpenCV 4.6 with
# the aruco contrib module), hole patterns (libs/config), the surface normal and the drilling
# area frame (PCL: src/core/perception/surface.cpp is the only source that includes it), the
# per-pixel depth averaging, a view written as PNG. A core: no DDS.
find_package(OpenCV REQUIRED COMPONENTS core imgproc imgcodecs calib3d aruco)
find_package(PCL 1.13 REQUIRED COMPONENTS common filters features search kdtree)

concert_core_library(concert_drill_perception STATIC
  src/core/perception/frame.cpp
  src/core/perception/blobs.cpp
  src/core/perception/aruco.cpp
  src/core/perception/patterns.cpp
  src/core/perception/surface.cpp
  src/core/perception/view_file.cpp)
target_include_directories(concert_drill_perception PUBLIC ${CMAKE_CURRENT_SOURCE_DIR}/include)
# OpenCV 4.6 as system headers (deprecated enum conversions are not ours); PCL's imported component
# targets bring theirs as system headers, and not the VTK and Qt libraries ${PCL_LIBRARIES} lists.
target_include_directories(concert_drill_perception SYSTEM PRIVATE ${OpenCV_INCLUDE_DIRS})
target_link_libraries(concert_drill_perception
  PUBLIC concert_hardware Eigen3::Eigen
  PRIVATE concert_world concert_config concert_common yaml-cpp
          opencv_core opencv_imgproc opencv_imgcodecs opencv_calib3d opencv_aruco
          pcl_common pcl_filters pcl_features pcl_search pcl_kdtree)

# Against the simulator's rendering of worlds with marks (libs/sim SceneCamera) and the world's
# ground truth (world::mark_truth).
concert_add_test(NAME perception_test
  SOURCES test/perception_test.cpp
  LIBS concert_drill_perception concert_sim concert_world opencv_imgcodecs
  LABELS drill
  TIMEOUT 300)
target_compile_definitions(perception_test PRIVATE
  DRILL_CONFIG_DIR="${CMAKE_CURRENT_SOURCE_DIR}/config"
  DRILL_FIXTURES="${CMAKE_CURRENT_SOURCE_DIR}/test/fixtures")
# The hand-drawn frames of the shape filters' test (cv::circle, cv::line).
target_include_directories(perception_test SYSTEM PRIVATE ${OpenCV_INCLUDE_DIRS})
target_link_libraries(perception_test PRIVATE opencv_core opencv_imgproc)
