#include "cli/common.h"

#include <algorithm>
#include <cctype>
#include <cstdlib>
#include <vector>

#include "volley/accel.h"

namespace volley::cli {

void add_kernel_options(CLI::App& cmd, KernelArgs& args) {
  cmd.add_option("--test", args.test, "Ray/triangle test: plane (notes' algorithm 1), moller (algorithm 2), watertight")
      ->check(CLI::IsMember({"plane", "moller", "watertight"}))
      ->capture_default_str();
  cmd.add_option("--isa", args.isa, "Kernel instruction set (VOLLEY_ISA also sets it)")
      ->check(CLI::IsMember({"auto", "scalar", "sse4.2", "avx2", "avx512"}))
      ->capture_default_str();
  cmd.add_option("--quality", args.quality,
                 "BVH build quality: medium (binned SAH) or high (also spatial splits: a slower build, faster "
                 "rays where triangles are long, e.g. Sponza; medium's answers but for ties that rounding decides)")
      ->check(CLI::IsMember({"medium", "high"}))
      ->capture_default_str();
  CLI::Option* fast = cmd.add_flag("--fast-slabs", args.fast_slabs,
                                   "Plain BVH box tests, no padding against rounding (faster; may miss a triangle "
                                   "whose box a ray only grazes)");
  cmd.add_flag("--reference", args.reference,
               "The accuracy reference: the scalar oracle with the triangle test in double precision and "
               "robust box tests (implies --isa scalar)")
      ->excludes(fast);
  cmd.add_option(
      "--scenes", args.scenes,
      "Folder of the benchmark meshes (${scenes}/ in scene files; scenes/fetch gets them): default $VOLLEY_SCENES, "
      "else ../shared/scenes, else scenes/downloads");
}

void add_threads_option(CLI::App& cmd, int& threads, const std::string& what) {
  cmd.add_option("--threads", threads, what + ": 0 (the default) for all cores, or a count")->check(CLI::Range(0, 1024));
}

CLI::Validator png_path() {
  return CLI::Validator(
      [](std::string& path) -> std::string {
        std::string ext = std::filesystem::path(path).extension().string();
        std::transform(ext.begin(), ext.end(), ext.begin(), [](unsigned char c) { return char(std::tolower(c)); });
        if (ext == ".png") return {};
        return "volley writes PNG images only: name the output FILE.png (got \"" + path + "\")";
      },
      "FILE.png");
}

Options kernel_options(const KernelArgs& args) {
  Options o;
  o.test = *parse_triangle_test(args.test);
  o.isa = *parse_isa(args.isa);
  o.robust = !args.fast_slabs;
  o.quality = *parse_build_quality(args.quality);
  o.reference_double = args.reference;
  if (args.reference && o.isa == Isa::automatic) o.isa = Isa::scalar;
  if (args.reference && o.isa != Isa::scalar)
    throw UsageError(
        "--reference runs the scalar oracle in double precision: use it without --isa (or with --isa "
        "scalar), not with --isa " +
        args.isa);
  return o;
}

std::optional<std::filesystem::path> project_dir_of_executable() {
  std::error_code ec;
  const std::filesystem::path exe = std::filesystem::read_symlink("/proc/self/exe", ec);
  if (ec) return std::nullopt;
  return exe.parent_path().parent_path().parent_path();  // <project>/build/<dir>/volley
}

std::filesystem::path shared_scenes_dir(const std::string& flag) {
  namespace fs = std::filesystem;
  if (!flag.empty()) return flag;
  if (const char* env = std::getenv("VOLLEY_SCENES"); env && *env) return env;
  std::vector<fs::path> candidates = {fs::current_path() / ".." / "shared" / "scenes"};
  if (const auto project = project_dir_of_executable()) candidates.push_back(*project / ".." / "shared" / "scenes");
  candidates.push_back(fs::current_path() / "scenes" / "downloads");  // where scenes/fetch puts them
  if (const auto project = project_dir_of_executable()) candidates.push_back(*project / "scenes" / "downloads");
  for (const auto& c : candidates)
    if (fs::is_directory(c)) return fs::weakly_canonical(c);
  return candidates.front();
}

}  // namespace volley::cli
