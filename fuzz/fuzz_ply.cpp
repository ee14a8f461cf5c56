// libFuzzer target: ASCII PLY. Bad input must end in io::LoadError; any other exception
// (std::bad_alloc from a count the header claims included), a crash or a sanitizer report
// is a finding.
#include <cstdint>
#include <optional>

#include "fuzz_file.h"
#include "io/load_error.h"
#include "io/ply_loader.h"
#include "io/scene_desc.h"

extern "C" int LLVMFuzzerTestOneInput(const std::uint8_t* data, std::size_t size) {
  const auto ply = volley_fuzz::write_input("in.ply", data, size);
  volley::io::SceneDesc scene;
  try {
    volley::io::load_ply(ply, glm::mat4(1.0f), std::nullopt, scene);
  } catch (const volley::io::LoadError&) {
  }
  return 0;
}
