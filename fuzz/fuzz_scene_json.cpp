// libFuzzer target: scene JSON (io::load_scene), with a small OBJ and PLY beside it that a
// scene may name ("mesh": "m.obj" / "m.ply"), and the renderer's scene set-up on what
// loads (materials, lights, camera, the Accel commit). Bad input must end in io::LoadError
// or volley::Error; anything else is a finding.
#include <cstdint>
#include <cstring>

#include "fuzz_file.h"
#include "io/load_error.h"
#include "io/scene_loader.h"
#include "render/scene.h"
#include "volley/accel.h"

namespace {

void write_text(const char* name, const char* text) {
  volley_fuzz::write_input(name, reinterpret_cast<const std::uint8_t*>(text), std::strlen(text));
}

}  // namespace

extern "C" int LLVMFuzzerTestOneInput(const std::uint8_t* data, std::size_t size) {
  static const bool meshes = [] {
    write_text("m.obj", "v 0 0 0\nv 1 0 0\nv 0 1 0\nv 0 0 1\nf 1 2 3\nf 1 2 4\nf 1 3 4\nf 2 3 4\n");
    write_text("m.ply",
               "ply\nformat ascii 1.0\nelement vertex 3\nproperty float x\nproperty float y\nproperty float z\n"
               "element face 1\nproperty list uchar int vertex_indices\nend_header\n0 0 0\n1 0 0\n0 1 0\n3 0 1 2\n");
    return true;
  }();
  (void)meshes;
  const auto json = volley_fuzz::write_input("in.json", data, size);
  try {
    const volley::io::SceneDesc desc = volley::io::load_scene(json, volley_fuzz::scratch_dir());
    volley::render::Scene scene(desc, 16, 12, volley::Options{});
  } catch (const volley::io::LoadError&) {
  } catch (const volley::Error&) {
  }
  return 0;
}
