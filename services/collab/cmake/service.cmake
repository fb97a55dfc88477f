# The service: the DDS adapter, main, `concert collab` verbs.
if(TARGET concert_dds)
  add_library(concert_collab_dds STATIC src/dds/collab_node.cpp)
  concert_target_defaults(concert_collab_dds)
  target_include_directories(concert_collab_dds PUBLIC ${CMAKE_CURRENT_SOURCE_DIR}/src)
  target_link_libraries(concert_collab_dds PUBLIC concert_collab_machine concert_collab_mpc concert_model
                        concert_model_dds concert_dds)

  add_executable(concert_collab src/main.cpp)
  concert_target_defaults(concert_collab)
  target_link_libraries(concert_collab PRIVATE concert_collab_dds concert_cli)

  # `concert collab ...` verbs (wired into the `concert` tool by its CMakeLists).
  add_library(concert_collab_cli STATIC src/cli/cli.cpp)
  concert_target_defaults(concert_collab_cli)
  target_include_directories(concert_collab_cli PUBLIC ${CMAKE_CURRENT_SOURCE_DIR}/include)
  target_link_libraries(concert_collab_cli PUBLIC concert_cli
                        PRIVATE concert_collab_voice concert_dds nlohmann_json::nlohmann_json)
endif()

if(TARGET concert_collab_dds)
  # The adapter in-process on a private domain, with the paper's transport arm generated from
  # deploy/demo/transport_robot.yaml (libs: module_db, simbus, topology, model_generation).
  concert_add_test(NAME collab_dds_test
    SOURCES test/dds_node_test.cpp
    LIBS concert_collab_dds concert_model_generation concert_module_db concert_simbus concert_topology concert_model_dds
    LABELS collab
    DDS
    TIMEOUT 120)
  target_compile_definitions(collab_dds_test PRIVATE CONCERT_SOURCE_DIR="${PROJECT_SOURCE_DIR}")
endif()
