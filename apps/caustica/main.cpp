// caustica: one binary, subcommands. See README.md for examples of each.
#include <cstdio>
#include <exception>
#include <map>
#include <string>

#include "commands.h"
#include "interrupt.h"
#include "options.h"

int main(int argc, char** argv) {
  CLI::App app{"caustica: a physically based renderer for comparing light transport algorithms"};
  app.require_subcommand(1);
  std::map<CLI::App*, caustica::cli::Runner> runners;
  auto add = [&](caustica::cli::Runner (*fn)(CLI::App&)) {
    const size_t before = app.get_subcommands({}).size();
    caustica::cli::Runner r = fn(app);
    runners[app.get_subcommands({})[before]] = std::move(r);
  };
  add(caustica::cli::add_render_command);
  add(caustica::cli::add_reference_command);
  add(caustica::cli::add_compare_command);
  add(caustica::cli::add_scenes_command);
  add(caustica::cli::add_integrators_command);
  add(caustica::cli::add_bench_command);
  try {
    app.parse(argc, argv);
  } catch (const CLI::CallForHelp& e) {
    return app.exit(e);
  } catch (const CLI::CallForAllHelp& e) {
    return app.exit(e);
  } catch (const CLI::ParseError& e) {
    // One line, like every other input error (app.exit() would add a second).
    caustica::cli::print_error(std::string(e.what()) + " (see --help)");
    return 2;
  }
  // Before any subcommand starts a worker thread, so that every thread runs with it.
  caustica::cli::install_interrupt_handler();
  for (auto& [sub, run] : runners)
    if (sub->parsed()) {
      try {
        return run();
      } catch (const std::exception& e) {
        caustica::cli::print_error(e.what());
        return 1;
      }
    }
  return 2;
}
