# The service: the rig and area detection (core), the DDS adapter, main, `concert drill` verbs.
concert_core_library(concert_drill_core STATIC src/core/drill_rig.cpp src/core/area_detection.cpp src/core/placement.cpp
  src/core/paths.cpp src/core/params.cpp src/core/plan_exchange.cpp src/core/inputs.cpp src/core/engine.cpp)
target_include_directories(concert_drill_core PUBLIC ${CMAKE_CURRENT_SOURCE_DIR}/include)
target_link_libraries(concert_drill_core
  PUBLIC concert_drill_tree concert_drill_control concert_drill_perception concert_model concert_kinematics
         concert_hardware concert_config concert_mobile_base concert_common Eigen3::Eigen
  PRIVATE concert_bim)

if(TARGET concert_dds)
  add_library(concert_drill_dds STATIC src/dds/drill_node.cpp src/dds/conversions.cpp)
  concert_target_defaults(concert_drill_dds)
  target_include_directories(concert_drill_dds PUBLIC ${CMAKE_CURRENT_SOURCE_DIR}/src)
  target_link_libraries(concert_drill_dds PUBLIC concert_drill_core concert_model_dds concert_sensors_dds concert_bim
                        concert_dds concert_mobile_base)

  add_executable(concert_drill src/main.cpp)
  concert_target_defaults(concert_drill)
  target_link_libraries(concert_drill PRIVATE concert_drill_dds concert_cli)
  target_compile_definitions(concert_drill PRIVATE
    CONCERT_DRILL_PATTERNS="${CMAKE_CURRENT_SOURCE_DIR}/config/patterns.yaml"
    CONCERT_DRILL_PARAMS="${CMAKE_CURRENT_SOURCE_DIR}/config/drill.yaml")

  # `concert drill ...` verbs (wired into the `concert` tool by its CMakeLists).
  add_library(concert_drill_cli STATIC src/cli/cli.cpp)
  concert_target_defaults(concert_drill_cli)
  target_include_directories(concert_drill_cli PUBLIC ${CMAKE_CURRENT_SOURCE_DIR}/include)
  target_link_libraries(concert_drill_cli PUBLIC concert_cli PRIVATE concert_dds nlohmann_json::nlohmann_json)

  # The DDS adapter on its own (no robot model): what it takes from the mission topic.
  concert_add_test(NAME drill_node_test
    SOURCES test/node_test.cpp
    LIBS concert_drill_dds
    LABELS drill
    TIMEOUT 60
    DDS)
endif()

# The mission engine without DDS: resends, acknowledgements, retries, stops, refusals.
concert_add_test(NAME drill_engine_test
  SOURCES test/engine_test.cpp
  LIBS concert_drill_core concert_test_model
  LABELS drill)

# Area location on frames the simulator's camera renders (libs/sim SceneCamera).
concert_add_test(NAME area_detection_test
  SOURCES test/area_detection_test.cpp
  LIBS concert_drill_core concert_sim concert_world
  LABELS drill
  TIMEOUT 120)

# The base placement of an area of several holes: its goal and the stand-or-move choice.
concert_add_test(NAME drill_placement_test
  SOURCES test/placement_test.cpp
  LIBS concert_drill_core
  LABELS drill)

# The tuning file: the shipped one holds every default; bad values name file, key and line.
concert_add_test(NAME drill_params_test
  SOURCES test/params_test.cpp
  LIBS concert_drill_core
  LABELS drill)
target_compile_definitions(drill_params_test PRIVATE CONCERT_DRILL_CONFIG_DIR="${CMAKE_CURRENT_SOURCE_DIR}/config")

# The drill's own joint-space paths: the way back, settles, the base kept where it stands.
concert_add_test(NAME drill_paths_test
  SOURCES test/paths_test.cpp test/plan_exchange_test.cpp test/inputs_test.cpp
  LIBS concert_drill_core
  LABELS drill)
