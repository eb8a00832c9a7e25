// libFuzzer harness of the STL mesh reader (ASCII and binary STL through assimp, then load_mesh).
#include "fuzz/mesh_fuzz.hpp"

extern "C" int LLVMFuzzerTestOneInput(const std::uint8_t* data, std::size_t size) {
  return ff::fuzz::read_mesh(data, size, "mesh.stl");
}
