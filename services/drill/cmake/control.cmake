# concert_drill_control: the closed-loop drilling motion (eq. 3) and the odometry's drift as the
# camera's marks tell it, no DDS.
concert_core_library(concert_drill_control STATIC src/core/drill_motion.cpp src/core/odometry_drift.cpp)
target_include_directories(concert_drill_control PUBLIC ${CMAKE_CURRENT_SOURCE_DIR}/include)
target_link_libraries(concert_drill_control PUBLIC Eigen3::Eigen)

concert_add_test(NAME drill_motion_test
  SOURCES test/drill_motion_test.cpp
  LIBS concert_drill_control
  LABELS drill)

concert_add_test(NAME odometry_drift_test
  SOURCES test/odometry_drift_test.cpp
  LIBS concert_drill_control
  LABELS drill)
