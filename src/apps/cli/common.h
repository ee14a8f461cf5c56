// Pieces shared by the volley subcommands.
#pragma once
#include <CLI/CLI.hpp>
#include <filesystem>
#include <optional>
#include <stdexcept>
#include <string>

#include "volley/options.h"

namespace volley::cli {

/// The exit statuses of every subcommand (README "Exit status"): 0 done, 1 a runtime error
/// (a bad input file, an unwritable output, out of memory), 2 a usage error (an unknown
/// option, a value out of range, options that do not go together), as POSIX tools do.
inline constexpr int kExitRuntimeError = 1;
inline constexpr int kExitUsageError = 2;

/// A command line that parsed but asks for something that cannot be: main() reports it as
/// a usage error (exit status 2).
struct UsageError : std::invalid_argument {
  using std::invalid_argument::invalid_argument;
};

/// Registers --threads: 0 (the default) runs on all cores, n on n threads, as in the C++,
/// C and Python APIs. `what` says what the threads do.
void add_threads_option(CLI::App& cmd, int& threads, const std::string& what = "Worker threads");

/// A validator for an output image path: PNG is the one format written, so another
/// extension is refused before any work is done.
CLI::Validator png_path();

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
/// Isa::scalar when --isa is auto; with another --isa it throws UsageError.
Options kernel_options(const KernelArgs& args);

/// Where ${scenes}/ points: --scenes, else VOLLEY_SCENES, else ../shared/scenes beside the
/// project, else the project's scenes/downloads (scenes/fetch's folder); the project is
/// found from the working directory or from the executable's location.
std::filesystem::path shared_scenes_dir(const std::string& flag);

/// The project folder of a volley built in <project>/build/<dir>/ (from /proc/self/exe);
/// nothing when the executable's path cannot be read.
std::optional<std::filesystem::path> project_dir_of_executable();

}  // namespace volley::cli
