# concert_collab_voice: "Hey CONCERT, <command>" with PocketSphinx (grammar + phone-loop rejection),
# audio files through libsndfile, resampling with soxr. Plain C++, no DDS.
find_package(PkgConfig REQUIRED)
# Not IMPORTED_TARGET: Debian's sphinxbase.pc names /usr/include/sphinxbase, which does not exist.
pkg_check_modules(SPHINX REQUIRED pocketsphinx sphinxbase)
set(COLLAB_SPHINX_INCLUDES "")
foreach(dir IN LISTS SPHINX_INCLUDE_DIRS)
  if(EXISTS ${dir})
    list(APPEND COLLAB_SPHINX_INCLUDES ${dir})
  endif()
endforeach()
pkg_check_modules(AUDIO REQUIRED IMPORTED_TARGET sndfile soxr)

concert_core_library(concert_collab_voice STATIC src/core/voice.cpp)
target_include_directories(concert_collab_voice PUBLIC ${CMAKE_CURRENT_SOURCE_DIR}/include)
target_include_directories(concert_collab_voice SYSTEM PRIVATE ${COLLAB_SPHINX_INCLUDES})
target_link_libraries(concert_collab_voice PUBLIC concert_collab_machine PRIVATE ${SPHINX_LIBRARIES} PkgConfig::AUDIO)

# Speech synthesised by espeak-ng at test time (deploy/packages/collab.txt).
concert_add_test(NAME collab_voice_test
  SOURCES test/voice_test.cpp
  LIBS concert_collab_voice
  LABELS collab
  TIMEOUT 300)
