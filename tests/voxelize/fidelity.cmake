# Exact fidelity of the voxelizer (lib/svokit/voxelize) against CGAL's exact kernel; included from
# tests/CMakeLists.txt. The Slow* tests (resolutions 256 and 512, ~80 s on 2 cores) get the ctest
# label "slow": `ctest -LE slow` skips them, `ctest -L slow` runs only them.
svokit_test(test_voxelize_fidelity
  SOURCES
    voxelize/exact_reference.cpp
    voxelize/voxelize_fidelity_test.cpp
    voxelize/solid_test_meshes.cpp
    voxelize/solid_fill_test.cpp
    voxelize/column_winding_test.cpp
    voxelize/winding_number_test.cpp
  LIBS CGAL::CGAL)

# gtest_discover_tests defines the tests when ctest runs, from an include file that also sets
# test_voxelize_fidelity_TESTS; this second include file, read after it, labels the Slow* ones.
file(WRITE "${CMAKE_CURRENT_BINARY_DIR}/test_voxelize_fidelity_labels.cmake" [=[
foreach(test IN LISTS test_voxelize_fidelity_TESTS)
  if(test MATCHES "^Slow")
    set_tests_properties("${test}" PROPERTIES LABELS slow)
  endif()
endforeach()
]=])
set_property(DIRECTORY APPEND PROPERTY TEST_INCLUDE_FILES
             "${CMAKE_CURRENT_BINARY_DIR}/test_voxelize_fidelity_labels.cmake")
