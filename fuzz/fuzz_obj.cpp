// libFuzzer target: Wavefront OBJ with its MTL. The bytes are written both as the OBJ and
// as fuzz.mtl beside it, so an input that says `mtllib fuzz.mtl` feeds its own statements
// to the MTL reader too (each reader skips what it does not know). Bad input must end in
// io::LoadError; any other exception, a crash or a sanitizer report is a finding.
#include <cstdint>
#include <cstdlib>
#include <optional>

#include "fuzz_file.h"
#include "io/load_error.h"
#include "io/obj_loader.h"
#include "io/scene_desc.h"

extern "C" int LLVMFuzzerTestOneInput(const std::uint8_t* data, std::size_t size) {
  const auto obj = volley_fuzz::write_input("in.obj", data, size);
  volley_fuzz::write_input("fuzz.mtl", data, size);
  volley::io::SceneDesc scene;
  try {
    volley::io::load_obj(obj, glm::mat4(1.0f), std::nullopt, scene);
  } catch (const volley::io::LoadError&) {
    // The expected answer to bad input.
  }
  return 0;
}
