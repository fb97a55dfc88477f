# --- The service: navigator core, DDS adapter, main, `concert nav` verbs ----------------------
target_sources(concert_nav_core PRIVATE src/core/navigator.cpp src/core/params.cpp)
target_link_libraries(concert_nav_core PRIVATE concert_config)

concert_add_test(NAME nav_navigator_test
  SOURCES test/navigator_test.cpp
  LIBS concert_nav_core concert_model_generation concert_simbus concert_module_db concert_topology
  LABELS nav
  TIMEOUT 300)
target_compile_definitions(nav_navigator_test PRIVATE NAV_CONFIG="${CMAKE_CURRENT_SOURCE_DIR}/config/nav.yaml")

if(TARGET concert_dds)
  add_library(concert_nav_dds STATIC src/dds/nav_node.cpp)
  concert_target_defaults(concert_nav_dds)
  target_include_directories(concert_nav_dds PUBLIC ${CMAKE_CURRENT_SOURCE_DIR}/src)
  target_link_libraries(concert_nav_dds PUBLIC concert_nav_core concert_model_dds concert_dds)

  add_executable(concert_nav src/main.cpp)
  concert_target_defaults(concert_nav)
  target_link_libraries(concert_nav PRIVATE concert_nav_dds concert_cli)

  # `concert nav ...` verbs (wired into the `concert` tool by its owner).
  add_library(concert_nav_cli STATIC src/cli/cli.cpp)
  concert_target_defaults(concert_nav_cli)
  target_include_directories(concert_nav_cli PUBLIC ${CMAKE_CURRENT_SOURCE_DIR}/include)
  target_link_libraries(concert_nav_cli PUBLIC concert_cli PRIVATE concert_dds nlohmann_json::nlohmann_json)
endif()
# --- end of the service -------------------------------------------------------------------------
