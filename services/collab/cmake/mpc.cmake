# concert_collab_mpc: the follow-me MPC (eq. 4) with obstacle avoidance (eq. 5) on Ipopt, and the
# obstacle grid (lidars + sonars -> spheres -> nearest per sector). Plain C++ + Eigen, no DDS.
find_package(PkgConfig REQUIRED)
pkg_check_modules(IPOPT REQUIRED IMPORTED_TARGET ipopt)

concert_core_library(concert_collab_mpc STATIC
  src/core/follow_me_mpc.cpp
  src/core/obstacle_map.cpp)
target_include_directories(concert_collab_mpc PUBLIC ${CMAKE_CURRENT_SOURCE_DIR}/include)
# Ipopt's headers as system headers (their shadowing and conversions are not ours).
target_include_directories(concert_collab_mpc SYSTEM PRIVATE ${IPOPT_INCLUDE_DIRS})
target_compile_options(concert_collab_mpc PRIVATE ${IPOPT_CFLAGS_OTHER})
target_link_libraries(concert_collab_mpc PUBLIC Eigen3::Eigen PRIVATE PkgConfig::IPOPT)

concert_add_test(NAME collab_mpc_test
  SOURCES test/mpc_test.cpp
  LIBS concert_collab_mpc
  LABELS collab
  TIMEOUT 120)

add_executable(bench_collab_mpc bench/bench_mpc.cpp)
concert_target_defaults(bench_collab_mpc)
target_link_libraries(bench_collab_mpc PRIVATE concert_collab_mpc)
