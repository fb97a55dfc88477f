# concert_drill_tree (see ../CMakeLists.txt): the mission file and the mission's behaviour tree
# over the MissionPorts interface. Plain C++, no DDS.
concert_core_library(concert_drill_tree STATIC
  src/core/mission.cpp)
target_include_directories(concert_drill_tree PUBLIC ${CMAKE_CURRENT_SOURCE_DIR}/include)
target_link_libraries(concert_drill_tree PUBLIC Eigen3::Eigen PRIVATE concert_common yaml-cpp)

concert_add_test(NAME drill_mission_test
  SOURCES test/mission_test.cpp
  LIBS concert_drill_tree concert_common
  LABELS drill)
