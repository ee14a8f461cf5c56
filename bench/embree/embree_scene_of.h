// A volley scene description as an Embree scene, for volley_vs_embree: the triangles of
// the objects a ray can see (mask not 0) as one mesh, and the scene's instances as
// Embree instance geometries under volley's geometry ids (so Embree's instID is volley's
// inst). Masks other than 0 and all bits are refused: they are not compared.
#pragma once
#include <algorithm>
#include <array>
#include <cstdint>
#include <stdexcept>
#include <string>
#include <vector>

#include "embree_scene.h"
#include "io/scene_desc.h"

namespace volley::bench {

inline EmbreeScene embree_scene_of(const io::SceneDesc& desc, const std::string& name, const EmbreeConfig& config) {
  const auto& mesh = desc.mesh;
  std::vector<std::uint32_t> visible;
  for (const io::ObjectDesc& o : mesh.objects) {
    if (o.mask == 0) continue;
    if (o.mask != kMaskAll) throw std::runtime_error(name + ": object masks other than 0 are not compared");
    visible.insert(visible.end(), mesh.indices.begin() + std::ptrdiff_t(3 * o.first_triangle),
                   mesh.indices.begin() + std::ptrdiff_t(3 * (o.first_triangle + o.triangle_count)));
  }
  if (mesh.objects.empty()) visible = mesh.indices;
  std::vector<EmbreeMesh> prototypes;
  std::vector<EmbreeInstance> instances;
  std::vector<std::int64_t> prototype_of(mesh.objects.size(), -1);
  for (std::size_t k = 0; k < desc.instances.size(); ++k) {
    const io::InstanceDesc& in = desc.instances[k];
    if (in.mask != kMaskAll) throw std::runtime_error(name + ": instance masks are not compared");
    const io::ObjectDesc& o = mesh.objects[in.object];
    if (prototype_of[in.object] < 0) {
      prototype_of[in.object] = std::int64_t(prototypes.size());
      prototypes.push_back({&mesh.positions[0].x, mesh.positions.size(), &mesh.indices[3 * o.first_triangle],
                            o.triangle_count});
    }
    EmbreeInstance e{std::size_t(prototype_of[in.object]), {}, unsigned(mesh.objects.size() + k)};
    const std::array<float, 12> rows = in.rows();
    std::copy(rows.begin(), rows.end(), e.transform);
    instances.push_back(e);
  }
  return EmbreeScene({mesh.positions.empty() ? nullptr : &mesh.positions[0].x, mesh.positions.size(), visible.data(),
                      visible.size() / 3},
                     prototypes, instances, config);
}

}  // namespace volley::bench
