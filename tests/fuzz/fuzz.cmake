# Fuzz targets, one per parser (tests/fuzz/README.md). With SVOKIT_FUZZ (clang) they link
# libFuzzer and scripts/fuzz runs them; otherwise a main that replays files. Either way the suite
# replays the seeds and every committed crash (tests/fuzz/crashes/TARGET/) through each target.
add_library(svokit_fuzz_target STATIC fuzz/fuzz_target.cpp)
target_link_libraries(svokit_fuzz_target PUBLIC svokit PRIVATE svokit_warnings)
target_include_directories(svokit_fuzz_target PUBLIC ${PROJECT_SOURCE_DIR})

add_executable(fuzz_seeds fuzz/fuzz_seeds.cpp)
target_link_libraries(fuzz_seeds PRIVATE svokit svokit_warnings draco::draco PkgConfig::OIIO)
target_include_directories(fuzz_seeds PRIVATE ${PROJECT_SOURCE_DIR})
set_target_properties(fuzz_seeds PROPERTIES RUNTIME_OUTPUT_DIRECTORY ${CMAKE_BINARY_DIR}/fuzz)
set(SVOKIT_FUZZ_SEEDS ${CMAKE_BINARY_DIR}/fuzz/seeds)
add_test(NAME Fuzz.Seeds COMMAND fuzz_seeds ${SVOKIT_FUZZ_SEEDS})
set_tests_properties(Fuzz.Seeds PROPERTIES FIXTURES_SETUP fuzz_seeds)

function(svokit_fuzz_target target source)
  add_executable(fuzz_${target} ${source})
  target_link_libraries(fuzz_${target} PRIVATE svokit_fuzz_target svokit_warnings)
  target_compile_definitions(fuzz_${target} PRIVATE ${ARGN})
  if(SVOKIT_FUZZ)
    target_link_options(fuzz_${target} PRIVATE -fsanitize=fuzzer)
  else()
    target_sources(fuzz_${target} PRIVATE fuzz/replay_main.cpp)
  endif()
  set_target_properties(fuzz_${target} PROPERTIES RUNTIME_OUTPUT_DIRECTORY ${CMAKE_BINARY_DIR}/fuzz)
  # -runs=0: libFuzzer runs each input of the folders once and exits (the replay main likewise).
  add_test(NAME Fuzz.${target}.SeedsAreAccepted
           COMMAND fuzz_${target} -runs=0 ${SVOKIT_FUZZ_SEEDS}/${target})
  set_tests_properties(Fuzz.${target}.SeedsAreAccepted PROPERTIES FIXTURES_REQUIRED fuzz_seeds
                       ENVIRONMENT SVOKIT_FUZZ_VALID_INPUTS=1)
  if(EXISTS ${CMAKE_CURRENT_SOURCE_DIR}/fuzz/crashes/${target})
    # One allocation over 2.1 GB fails a replay: the limit scripts/fuzz sets for `image` (the
    # other targets' campaigns allow 4 GB; none of their committed inputs comes near either).
    add_test(NAME Fuzz.${target}.CrashesAreFixed
             COMMAND fuzz_${target} -runs=0 -malloc_limit_mb=2100 -rss_limit_mb=4096
                     ${CMAKE_CURRENT_SOURCE_DIR}/fuzz/crashes/${target})
  endif()
endfunction()

foreach(ext obj ply off stl gltf glb drc)
  svokit_fuzz_target(${ext} fuzz/fuzz_mesh.cpp SVOKIT_FUZZ_EXT="${ext}")
endforeach()
foreach(format svm vfrag svo)
  svokit_fuzz_target(${format} fuzz/fuzz_container.cpp SVOKIT_FUZZ_FORMAT="${format}")
endforeach()
svokit_fuzz_target(image fuzz/fuzz_image.cpp)
# .svopart: read, every page checked, merged alone and the result validated (svokit_validate).
svokit_fuzz_target(svopart fuzz/fuzz_svopart.cpp)
target_link_libraries(fuzz_svopart PRIVATE svokit_validate)
