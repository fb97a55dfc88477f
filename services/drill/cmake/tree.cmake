# concert_drill_tree (see ../CMakeLists.txt): the mission file and the mission's behaviour tree
# over the MissionPorts interface, with its own small behaviour-tree engine (src/core/bt: see
# bt.hpp for why not BehaviorTree.CPP). Plain C++, no DDS.
concert_core_library(concert_drill_tree STATIC
  src/core/mission.cpp
  src/core/mission_tree.cpp
  src/core/bt/bt.cpp)
target_include_directories(concert_drill_tree
  PUBLIC ${CMAKE_CURRENT_SOURCE_DIR}/include
  PRIVATE ${CMAKE_CURRENT_SOURCE_DIR}/src/core)
target_link_libraries(concert_drill_tree PUBLIC Eigen3::Eigen PRIVATE concert_common yaml-cpp)

concert_add_test(NAME drill_mission_test
  SOURCES test/mission_test.cpp
  LIBS concert_drill_tree concert_common
  LABELS drill)

concert_add_test(NAME drill_mission_tree_test
  SOURCES test/mission_tree_test.cpp
  LIBS concert_drill_tree concert_common
  LABELS drill)
target_include_directories(drill_mission_tree_test PRIVATE ${CMAKE_CURRENT_SOURCE_DIR}/src/core)
