# Per-voxel attribute sampling (lib/svokit/voxelize/attributes.*, column_areas.cpp) and the texture
# sampler (lib/svokit/mesh/texture_sampler.*). Included from tests/CMakeLists.txt.
svokit_test(test_attribute_sampler SOURCES voxelize/attribute_sampler_test.cpp)
