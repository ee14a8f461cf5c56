// Pieces shared by the volley subcommands.
#pragma once
#include <CLI/CLI.hpp>
#include <filesystem>
#include <optional>
#include <string>

#include "volley/options.h"

namespace volley::cli {

/// Options every tracing subcommand takes (--test, --isa, --quality, --fast-slabs, --reference, --scenes).
struct KernelArgs {
  std::string test = "watertight";
  std::string isa = "auto";
  std::string quality = "medium";  ///< Options::quality
  bool fast_slabs = false;  ///< Options::robust = false
  bool reference = false;   ///< Options::reference_double on Isa::scalar
  std::string scenes;       ///< folder of shared meshes for ${scenes}/ paths in scene files
};

/// Registers --test, --isa, --quality, --fast-slabs, --reference and --scenes on a subcommand.
void add_kernel_options(CLI::App& cmd, KernelArgs& args);

/// The Accel options the arguments name (validated by CLI11 already). --reference picks
/// Isa::scalar when --isa is auto; with another --isa it throws volley::Error.
Options kernel_options(const KernelArgs& args);

/// Where ${scenes}/ points: --scenes, else VOLLEY_SCENES, else ../shared/scenes beside the
/// project (found from the working directory or from the executable's location).
std::filesystem::path shared_scenes_dir(const std::string& flag);

/// The project folder of a volley built in <project>/build/<dir>/ (from /proc/self/exe);
/// nothing when the executable's path cannot be read.
std::optional<std::filesystem::path> project_dir_of_executable();

}  // namespace volley::cli
