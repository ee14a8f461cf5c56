// volley: command-line front end. Each subcommand lives in its own file (cmd_*.cpp).
#include <cstdio>
#include <exception>
#include <new>

#include <CLI/CLI.hpp>

#include "cli/commands.h"
#include "cli/common.h"
#include "core/tsan_one_thread.h"  // (ThreadSanitizer build only)
#include "io/load_error.h"
#include "volley/accel.h"

int main(int argc, char** argv) {
  CLI::App app{
      "volley: a data-oriented SIMD packet ray tracer.\n"
      "SCENE is a .json scene (see README) or a mesh (.obj/.ply, which gets an automatic\n"
      "camera, light and material). Examples:\n"
      "  volley render scenes/cornell.json -o out/cornell.png --spp 16\n"
      "  volley render scenes/cornell.json --integrator path --spp 64\n"
      "  volley info scenes/meshes/sphere.obj\n"
      "Exit status: 0 done, 1 a runtime error (bad input file, unwritable output), 2 a usage error."};
  app.require_subcommand(1);
  app.set_version_flag("--version", "volley 0.1.0");
  volley::cli::register_commands(app);
  try {
    app.parse(argc, argv);
  } catch (const CLI::ParseError& e) {
    if (e.get_exit_code() == 0) return app.exit(e);  // --help, --version
    std::fprintf(stderr, "volley: error: %s\nRun 'volley --help' or 'volley COMMAND --help' for the options.\n",
                 e.what());
    return volley::cli::kExitUsageError;
  }
  try {
    return volley::cli::run_selected(app);
  } catch (const volley::cli::UsageError& e) {
    std::fprintf(stderr, "volley: error: %s\n", e.what());
    return volley::cli::kExitUsageError;
  } catch (const volley::io::LoadError& e) {
    std::fprintf(stderr, "volley: error: %s\n", e.what());
  } catch (const volley::Error& e) {
    std::fprintf(stderr, "volley: error: %s\n", e.what());
  } catch (const std::bad_alloc&) {
    std::fprintf(stderr, "volley: error: out of memory (the scene or ray file is larger than this machine can hold)\n");
  } catch (const std::exception& e) {
    std::fprintf(stderr, "volley: error: %s\n", e.what());
  }
  return volley::cli::kExitRuntimeError;
}
