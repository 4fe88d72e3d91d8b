# Per-voxel attribute sampling (lib/svokit/voxelize/attributes.*) and the texture sampler
# (lib/svokit/mesh/texture_sampler.*). Included from tests/CMakeLists.txt.
svokit_test(test_voxelize_attributes SOURCES voxelize/attributes_test.cpp)
