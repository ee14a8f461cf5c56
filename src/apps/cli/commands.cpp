#include "cli/commands.h"

#include <utility>
#include <vector>

#include "cli/common.h"

namespace volley::cli {
namespace {

std::vector<std::pair<CLI::App*, Runner>>& registry() {
  static std::vector<std::pair<CLI::App*, Runner>> commands;
  return commands;
}

void add(CLI::App& app, Runner (*registrar)(CLI::App&)) {
  const std::size_t before = app.get_subcommands({}).size();
  Runner run = registrar(app);
  registry().emplace_back(app.get_subcommands({})[before], std::move(run));
}

}  // namespace

void register_commands(CLI::App& app) {
  add(app, register_render);
  add(app, register_info);
  add(app, register_rays);
  add(app, register_trace);
  add(app, register_points);
  add(app, register_query);
  add(app, register_accuracy);
}

int run_selected(const CLI::App&) {
  for (auto& [cmd, run] : registry())
    if (cmd->parsed()) return run();
  return kExitUsageError;
}

}  // namespace volley::cli
