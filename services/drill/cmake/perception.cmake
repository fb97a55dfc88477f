# concert_drill_perception (see ../CMakeLists.txt): hole patterns of ArUco markers (libs/config).
# A core: no DDS.
concert_core_library(concert_drill_perception STATIC
  src/core/perception/patterns.cpp)
target_include_directories(concert_drill_perception PUBLIC ${CMAKE_CURRENT_SOURCE_DIR}/include)
target_link_libraries(concert_drill_perception
  PUBLIC Eigen3::Eigen
  PRIVATE concert_world concert_config concert_common yaml-cpp)

concert_add_test(NAME perception_test
  SOURCES test/perception_test.cpp
  LIBS concert_drill_perception
  LABELS drill)
target_compile_definitions(perception_test PRIVATE
  DRILL_CONFIG_DIR="${CMAKE_CURRENT_SOURCE_DIR}/config"
  DRILL_FIXTURES="${CMAKE_CURRENT_SOURCE_DIR}/test/fixtures")
