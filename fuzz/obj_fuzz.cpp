// libFuzzer harness of the OBJ mesh reader (Wavefront OBJ through assimp, then load_mesh).
#include "fuzz/mesh_fuzz.hpp"

extern "C" int LLVMFuzzerTestOneInput(const std::uint8_t* data, std::size_t size) {
  return ff::fuzz::read_mesh(data, size, "mesh.obj");
}
