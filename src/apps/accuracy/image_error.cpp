#include "accuracy/image_error.h"

#include <algorithm>
#include <cmath>

#include "accuracy/runner.h"
#include "io/png_writer.h"
#include "io/scene_loader.h"
#include "render/renderer.h"

namespace volley::accuracy {
namespace {

render::RenderResult render_with(const io::SceneDesc& desc, int size, const Options& options) {
  const render::Scene scene(desc, size, size, options);
  render::RenderOptions ro;
  ro.spp = 1;
  ro.max_depth = desc.settings.max_depth;
  ro.integrator = desc.settings.integrator == "path" ? render::IntegratorKind::path : render::IntegratorKind::whitted;
  ro.seed = desc.settings.seed;
  ro.threads = 1;
  return render::render(scene, ro);
}

float display(float linear) { return std::isnan(linear) ? 0.0f : io::linear_to_srgb(std::clamp(linear, 0.0f, 1.0f)); }

void compare(const render::Image& reference, const render::Image& image, ImageRow& row) {
  double sum = 0;
  for (std::size_t i = 0; i < image.pixels.size(); ++i) {
    const glm::vec3 p = image.pixels[i], q = reference.pixels[i];
    row.nan_pixels += std::isnan(p.x) || std::isnan(p.y) || std::isnan(p.z);
    for (int c = 0; c < 3; ++c) {
      const double d = double(display(p[c])) - double(display(q[c]));
      sum += d * d;
    }
  }
  row.rmse = std::sqrt(sum / double(3 * std::max<std::size_t>(1, image.pixels.size())));
  row.psnr = row.rmse > 0 ? 20.0 * std::log10(1.0 / row.rmse) : INFINITY;
}

}  // namespace

std::vector<ImageRow> image_error(const std::filesystem::path& scene_file, const std::filesystem::path& scenes_dir,
                                  int size, const std::vector<TriangleTest>& tests, const std::vector<Isa>& isas,
                                  const std::function<void()>& step) {
  const io::SceneDesc desc = io::load_scene(scene_file, scenes_dir);
  std::vector<ImageRow> rows;
  const auto row_of = [&](const render::RenderResult& r, const Options& o, bool is_reference) {
    ImageRow row;
    row.scene = scene_file.filename().string();
    row.test = o.test, row.isa = o.isa, row.reference = is_reference;
    row.width = r.image.width, row.height = r.image.height;
    row.seconds = r.seconds;
    return row;
  };
  const Options ref_options = reference_options();
  const render::RenderResult reference = render_with(desc, size, ref_options);
  rows.push_back(row_of(reference, ref_options, true));
  compare(reference.image, reference.image, rows.back());
  if (step) step();
  for (TriangleTest test : tests)
    for (Isa isa : isas) {
      Options o;
      o.test = test, o.isa = isa, o.robust = true;
      const render::RenderResult r = render_with(desc, size, o);
      rows.push_back(row_of(r, o, false));
      compare(reference.image, r.image, rows.back());
      if (step) step();
    }
  return rows;
}

}  // namespace volley::accuracy
