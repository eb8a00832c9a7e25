// The mesh harnesses (stl_fuzz.cpp, obj_fuzz.cpp): the input written to a file of the format's
// extension, by which assimp picks its importer, and read by load_mesh as a world's `mesh:` obstacle
// is (world/mesh: assimp, then FCL's bounding-volume tree). Every rejection must be a std::exception.
#pragma once

#include <cstdint>
#include <exception>
#include <string>

#include "fuzz/fuzz_support.hpp"
#include "world/mesh.hpp"

namespace ff::fuzz {

inline int read_mesh(const std::uint8_t* data, std::size_t size, const std::string& name) {
  const std::string path = scratch().write(name, text_of(data, size));
  try {
    (void)load_mesh(path, Vec3(1.0, 2.0, 0.5));
  } catch (const std::exception&) {
  }
  return 0;
}

}  // namespace ff::fuzz
