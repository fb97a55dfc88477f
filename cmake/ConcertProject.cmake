# The one CMake helper of the project: language level, warnings, sanitizers, coverage,
# the layout rules checked at configure time (a core links no DDS; no service links another
# service), and tests.
include_guard(GLOBAL)

set(CMAKE_CXX_STANDARD 20)
set(CMAKE_CXX_STANDARD_REQUIRED ON)
set(CMAKE_CXX_EXTENSIONS OFF)
set(CMAKE_POSITION_INDEPENDENT_CODE ON)
set(CMAKE_EXPORT_COMPILE_COMMANDS ON)
if(NOT CMAKE_BUILD_TYPE AND NOT CMAKE_CONFIGURATION_TYPES)
  set(CMAKE_BUILD_TYPE RelWithDebInfo CACHE STRING "Build type" FORCE)
endif()

option(CONCERT_WERROR "Treat warnings in project code as errors" ON)
set(CONCERT_SANITIZE "" CACHE STRING "Sanitizers for project code, e.g. address,undefined or thread")
option(CONCERT_COVERAGE "Instrument project code for gcov/lcov coverage" OFF)
# The fuzzing build (`make fuzz`, tests/fuzz/README.md): clang, project code instrumented for
# libFuzzer with AddressSanitizer and UndefinedBehaviorSanitizer (every finding aborts), and
# assertions kept (no NDEBUG).
option(CONCERT_FUZZ "Build the fuzz targets with libFuzzer (clang), sanitizers and assertions" OFF)

find_program(CCACHE_PROGRAM ccache)
if(CCACHE_PROGRAM)
  set(CMAKE_C_COMPILER_LAUNCHER ${CCACHE_PROGRAM})
  set(CMAKE_CXX_COMPILER_LAUNCHER ${CCACHE_PROGRAM})
endif()

add_library(concert_build_options INTERFACE)
target_compile_options(concert_build_options INTERFACE
  -Wall -Wextra -Wpedantic -Wshadow -Wconversion -Wno-sign-conversion -Wno-missing-field-initializers
  $<$<COMPILE_LANGUAGE:CXX>:-Wnon-virtual-dtor>
  $<$<BOOL:${CONCERT_WERROR}>:-Werror>)
if(CONCERT_SANITIZE)
  target_compile_options(concert_build_options INTERFACE -fsanitize=${CONCERT_SANITIZE} -fno-omit-frame-pointer)
  target_link_options(concert_build_options INTERFACE -fsanitize=${CONCERT_SANITIZE})
endif()
if(CONCERT_FUZZ)
  if(NOT CMAKE_CXX_COMPILER_ID STREQUAL "Clang")
    message(FATAL_ERROR "CONCERT_FUZZ needs clang (libFuzzer): configure with CXX=clang++-16 CC=clang-16")
  endif()
  target_compile_options(concert_build_options INTERFACE
    -fsanitize=fuzzer-no-link,address,undefined -fno-sanitize-recover=all -fno-omit-frame-pointer
    -UNDEBUG)
  target_link_options(concert_build_options INTERFACE -fsanitize=address,undefined)
endif()
if(CONCERT_COVERAGE)
  target_compile_options(concert_build_options INTERFACE --coverage -O0)
  target_link_options(concert_build_options INTERFACE --coverage)
endif()

# Project code (not generated code) gets the strict options.
function(concert_target_defaults target)
  target_link_libraries(${target} PRIVATE concert_build_options)
endfunction()

# A service or library core: plain C++, no DDS. Checked at the end of configuration.
set_property(GLOBAL PROPERTY CONCERT_CORE_LIBRARIES "")
function(concert_core_library target)
  add_library(${target} ${ARGN})
  concert_target_defaults(${target})
  set_property(GLOBAL APPEND PROPERTY CONCERT_CORE_LIBRARIES ${target})
endfunction()

set(CONCERT_DDS_LINK_PATTERN "fastrtps|fastcdr|fastdds|CycloneDDS|ddsc|concert_dds|concert_idl_")

# Direct link dependencies of a target (private and interface, $<LINK_ONLY:> unwrapped), once each.
function(_concert_direct_links target out_var)
  get_target_property(type ${target} TYPE)
  set(links "")
  if(NOT type STREQUAL "INTERFACE_LIBRARY")
    get_target_property(direct ${target} LINK_LIBRARIES)
    if(direct)
      list(APPEND links ${direct})
    endif()
  endif()
  get_target_property(iface ${target} INTERFACE_LINK_LIBRARIES)
  if(iface)
    list(APPEND links ${iface})
  endif()
  set(deps "")
  foreach(l IN LISTS links)
    string(REGEX REPLACE "^\\$<LINK_ONLY:(.*)>$" "\\1" l "${l}")
    list(APPEND deps ${l})
  endforeach()
  list(REMOVE_DUPLICATES deps)
  set(${out_var} ${deps} PARENT_SCOPE)
endfunction()

function(_concert_collect_links target out_var)
  set(seen "")
  set(queue ${target})
  while(queue)
    list(POP_FRONT queue item)
    if(item IN_LIST seen OR NOT TARGET ${item})
      list(APPEND seen ${item})
      continue()
    endif()
    list(APPEND seen ${item})
    _concert_direct_links(${item} links)
    list(APPEND queue ${links})
  endwhile()
  set(${out_var} ${seen} PARENT_SCOPE)
endfunction()

function(concert_check_core_libraries)
  get_property(cores GLOBAL PROPERTY CONCERT_CORE_LIBRARIES)
  foreach(core IN LISTS cores)
    _concert_collect_links(${core} deps)
    foreach(dep IN LISTS deps)
      if(dep MATCHES "${CONCERT_DDS_LINK_PATTERN}")
        message(FATAL_ERROR "Core library '${core}' links '${dep}': a core must not depend on DDS. "
                            "Move the DDS code into the service's src/dds adapter.")
      endif()
    endforeach()
  endforeach()
endfunction()

# Every target defined in the source tree (recursively from `dir`).
function(_concert_all_targets dir out_var)
  get_property(targets DIRECTORY ${dir} PROPERTY BUILDSYSTEM_TARGETS)
  get_property(subdirs DIRECTORY ${dir} PROPERTY SUBDIRECTORIES)
  foreach(sub IN LISTS subdirs)
    _concert_all_targets(${sub} more)
    list(APPEND targets ${more})
  endforeach()
  set(${out_var} ${targets} PARENT_SCOPE)
endfunction()

# The service a target belongs to (the <name> of services/<name>/...), or "" outside services/.
function(_concert_service_of target out_var)
  set(service "")
  if(TARGET ${target})
    get_target_property(aliased ${target} ALIASED_TARGET)
    if(aliased)
      set(target ${aliased})
    endif()
    get_target_property(imported ${target} IMPORTED)
    if(NOT imported)
      get_target_property(dir ${target} SOURCE_DIR)
      file(RELATIVE_PATH rel ${CMAKE_SOURCE_DIR} ${dir})
      if(rel MATCHES "^services/([^/]+)")
        set(service ${CMAKE_MATCH_1})
      endif()
    endif()
  endif()
  set(${out_var} "${service}" PARENT_SCOPE)
endfunction()

# No service links another service: what two services share goes into libs/. Every target
# defined under services/<a>/ is checked against its direct link dependencies; one defined under
# services/<b>/ (b != a) fails configuration, naming both targets. There is no exception list:
# a shared piece of code moves to libs/.
function(concert_check_service_links)
  _concert_all_targets(${CMAKE_SOURCE_DIR} targets)
  set(errors "")
  foreach(target IN LISTS targets)
    _concert_service_of(${target} service)
    if(service STREQUAL "")
      continue()
    endif()
    _concert_direct_links(${target} deps)
    foreach(dep IN LISTS deps)
      _concert_service_of(${dep} other)
      if(other STREQUAL "" OR other STREQUAL service)
        continue()
      endif()
      string(APPEND errors "\n  '${target}' (services/${service}) links '${dep}' (services/${other})")
    endforeach()
  endforeach()
  if(errors)
    message(FATAL_ERROR "A service links another service:${errors}\n"
                        "Services are independent: move what they share into libs/ (docs/architecture.md, section 4).")
  endif()
endfunction()

# Both layout checks, once every target is known (call from the top-level CMakeLists.txt).
function(concert_check_layout)
  concert_check_core_libraries()
  concert_check_service_links()
endfunction()

# Tests that talk DDS each get their own domain id (CONCERT_DOMAIN_ID), so `ctest -j` never
# mixes two tests' traffic. Ids from CONCERT_TEST_DOMAIN_BASE on are handed out in
# configuration order, up to 100: RTPS puts domain d on UDP ports 7400 + 250 d onwards, and from
# domain 101 on those lie in Linux's ephemeral port range (32768-60999), where the transmit
# socket of a Cyclone DDS participant of one test may land in another test's band and join its
# domain (libs/dds/README.md). Two build trees on one machine whose tests may run at the same
# time take bases far enough apart (e.g. 1 and 50).
set(CONCERT_TEST_DOMAIN_BASE 50 CACHE STRING "First DDS domain id handed to the tests (1 to 100)")
set(CONCERT_TEST_DOMAIN_LAST 100)
# A build tree configured when the tests' domains went up to 229 may keep a base of 100 or more
# in its cache: such a tree takes the default instead of failing to configure.
if(CONCERT_TEST_DOMAIN_BASE GREATER_EQUAL 100)
  message(STATUS "CONCERT_TEST_DOMAIN_BASE: ${CONCERT_TEST_DOMAIN_BASE} leaves no room for the DDS tests "
                 "below domain 101; using 50")
  set(CONCERT_TEST_DOMAIN_BASE 50 CACHE STRING "First DDS domain id handed to the tests (1 to 100)" FORCE)
endif()
if(CONCERT_TEST_DOMAIN_BASE LESS 1 OR CONCERT_TEST_DOMAIN_BASE GREATER CONCERT_TEST_DOMAIN_LAST)
  message(FATAL_ERROR "CONCERT_TEST_DOMAIN_BASE=${CONCERT_TEST_DOMAIN_BASE}: must be 1 to "
                      "${CONCERT_TEST_DOMAIN_LAST} (0 is the robot's own domain; above "
                      "${CONCERT_TEST_DOMAIN_LAST} the ports lie in the ephemeral range)")
endif()
set_property(GLOBAL PROPERTY CONCERT_NEXT_TEST_DOMAIN ${CONCERT_TEST_DOMAIN_BASE})
function(concert_next_test_domain out_var)
  get_property(id GLOBAL PROPERTY CONCERT_NEXT_TEST_DOMAIN)
  if(id GREATER CONCERT_TEST_DOMAIN_LAST)
    message(FATAL_ERROR "More DDS tests than test domain ids "
                        "(${CONCERT_TEST_DOMAIN_BASE}..${CONCERT_TEST_DOMAIN_LAST}): lower "
                        "CONCERT_TEST_DOMAIN_BASE (cmake -DCONCERT_TEST_DOMAIN_BASE=50 <build dir>)")
  endif()
  math(EXPR next "${id} + 1")
  set_property(GLOBAL PROPERTY CONCERT_NEXT_TEST_DOMAIN ${next})
  set(${out_var} ${id} PARENT_SCOPE)
endfunction()

# Unit/integration test from sources, linked with GoogleTest and GoogleMock (matchers such as
# HasSubstr), registered with ctest.
#   concert_add_test(NAME name SOURCES a.cpp ... LIBS lib ... [LABELS l ...] [TIMEOUT s] [DDS] [MANUAL])
#   MANUAL: the test program is built but not registered with ctest (make chaos runs one).
# DDS: the test gets a private CONCERT_DOMAIN_ID and the label "dds".
set(CONCERT_TEST_SUPPORT_DIR ${CMAKE_CURRENT_LIST_DIR}/../tests/support)
# Test data shared by libraries and services (robot URDFs: tests/fixtures/README.md); a library's
# tests read these, never another component's test folder.
set(CONCERT_TEST_FIXTURES_DIR ${CMAKE_CURRENT_LIST_DIR}/../tests/fixtures)
function(concert_add_test)
  cmake_parse_arguments(T "DDS;MANUAL" "NAME;TIMEOUT" "SOURCES;LIBS;LABELS" ${ARGN})
  add_executable(${T_NAME} ${T_SOURCES})
  concert_target_defaults(${T_NAME})
  target_link_libraries(${T_NAME} PRIVATE ${T_LIBS} GTest::gmock GTest::gtest GTest::gtest_main Threads::Threads)
  # tests/support: header-only helpers every test may include (test_data.hpp).
  target_include_directories(${T_NAME} PRIVATE ${CONCERT_TEST_SUPPORT_DIR})
  target_compile_definitions(${T_NAME} PRIVATE
    CONCERT_SHARED_DATA="${CONCERT_SHARED_DATA}"
    CONCERT_SOURCE_DIR="${PROJECT_SOURCE_DIR}")
  if(T_MANUAL)
    return()  # built, run by hand or by a make target, not by ctest
  endif()
  if(NOT T_TIMEOUT)
    set(T_TIMEOUT 120)
  endif()
  add_test(NAME ${T_NAME} COMMAND ${T_NAME})
  set_tests_properties(${T_NAME} PROPERTIES TIMEOUT ${T_TIMEOUT} LABELS "${T_LABELS}")
  if(T_DDS)
    concert_next_test_domain(domain)
    set_tests_properties(${T_NAME} PROPERTIES
      ENVIRONMENT "CONCERT_DOMAIN_ID=${domain}" LABELS "dds;${T_LABELS}")
  endif()
endfunction()
