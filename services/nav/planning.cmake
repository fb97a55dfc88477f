# Planning and control of the nav service (issue #16): layered costmap, A* global planner, local
# controller (core sources of concert_nav_core), their tests and the planning benchmark.
# Included by services/nav/CMakeLists.txt after concert_nav_core is defined.
target_sources(concert_nav_core PRIVATE
  ${CMAKE_CURRENT_LIST_DIR}/src/core/costmap.cpp
  ${CMAKE_CURRENT_LIST_DIR}/src/core/global_planner.cpp
  ${CMAKE_CURRENT_LIST_DIR}/src/core/local_controller.cpp)

# Synthetic buildings (rooms and doors), lidar ray casting and the kinematic closed loop shared
# by the planning tests and the benchmark.
add_library(concert_nav_planning_fixtures STATIC ${CMAKE_CURRENT_LIST_DIR}/test/planning_fixtures.cpp)
concert_target_defaults(concert_nav_planning_fixtures)
target_include_directories(concert_nav_planning_fixtures PUBLIC ${CMAKE_CURRENT_LIST_DIR}/test)
target_link_libraries(concert_nav_planning_fixtures PUBLIC concert_nav_core)

concert_add_test(NAME nav_costmap_test
  SOURCES ${CMAKE_CURRENT_LIST_DIR}/test/costmap_test.cpp
  LIBS concert_nav_planning_fixtures
  LABELS nav)
concert_add_test(NAME nav_global_planner_test
  SOURCES ${CMAKE_CURRENT_LIST_DIR}/test/global_planner_test.cpp
  LIBS concert_nav_planning_fixtures
  LABELS nav)
concert_add_test(NAME nav_local_controller_test
  SOURCES ${CMAKE_CURRENT_LIST_DIR}/test/local_controller_test.cpp
  LIBS concert_nav_planning_fixtures
  LABELS nav
  TIMEOUT 300)

add_executable(bench_global_planner ${CMAKE_CURRENT_LIST_DIR}/bench/bench_global_planner.cpp)
concert_target_defaults(bench_global_planner)
target_link_libraries(bench_global_planner PRIVATE concert_cli concert_nav_planning_fixtures)
