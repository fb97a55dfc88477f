# concert_collab_machine: Fig. 12's state machine and the text command parser. Plain C++, no DDS.
concert_core_library(concert_collab_machine STATIC
  src/core/state_machine.cpp
  src/core/command_parser.cpp)
target_include_directories(concert_collab_machine PUBLIC ${CMAKE_CURRENT_SOURCE_DIR}/include)

concert_add_test(NAME collab_state_machine_test
  SOURCES test/state_machine_test.cpp
  LIBS concert_collab_machine
  LABELS collab)
