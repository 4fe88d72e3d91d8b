// The one translation unit that compiles tinygltf. Image decoding is off: textures stay encoded
// and are decoded lazily (svokit/mesh/image_codec.hpp); external images are loaded
// by svokit itself so a missing one is a warning, not a failed import.
#define TINYGLTF_IMPLEMENTATION
#define TINYGLTF_NO_STB_IMAGE
#define TINYGLTF_NO_STB_IMAGE_WRITE
#define TINYGLTF_NO_EXTERNAL_IMAGE
#define TINYGLTF_USE_CPP14
#include <tiny_gltf.h>
