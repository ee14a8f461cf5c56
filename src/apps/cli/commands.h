// Subcommand registry: each cmd_*.cpp adds a subcommand with its options and the function
// that runs it; main() parses, then runs the chosen one inside its error handler.
#pragma once
#include <functional>

#include <CLI/CLI.hpp>

namespace volley::cli {

using Runner = std::function<int()>;

/// Adds every subcommand to the app.
void register_commands(CLI::App& app);
/// Runs the subcommand the parsed command line chose; returns the exit status.
int run_selected(const CLI::App& app);

/// Each of these adds one subcommand and returns its runner (which reads the options
/// bound at registration).
Runner register_render(CLI::App& app);
Runner register_info(CLI::App& app);
Runner register_rays(CLI::App& app);
Runner register_trace(CLI::App& app);
Runner register_accuracy(CLI::App& app);
Runner register_points(CLI::App& app);
Runner register_query(CLI::App& app);

}  // namespace volley::cli
