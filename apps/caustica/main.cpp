// caustica: one binary, subcommands. See README.md for examples of each.
#include <cstdio>
#include <exception>
#include <map>
#include <memory>
#include <string>

#include "commands.h"
#include "interrupt.h"
#include "options.h"
#include "ranks_cli.h"
#include "render/ranks.h"

int main(int argc, char** argv) {
  // First: MPI_Init must precede every thread. Its destructor (MPI_Finalize) runs at return.
  std::unique_ptr<caustica::Ranks> ranks = caustica::start_ranks(&argc, &argv);
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
  bool help = false;
  const int parsed = caustica::cli::prepare_on_all_ranks(*ranks, [&] {
    try {
      app.parse(argc, argv);
    } catch (const CLI::CallForHelp& e) {
      help = true;
      return ranks->is_root() ? app.exit(e) : 0;  // one help text under mpirun
    } catch (const CLI::CallForAllHelp& e) {
      help = true;
      return ranks->is_root() ? app.exit(e) : 0;
    } catch (const CLI::ParseError& e) {
      // One line, like every other input error (app.exit() would add a second).
      caustica::cli::print_error(std::string(e.what()) + " (see --help)");
      return 2;
    }
    return 0;
  });
  if (parsed != 0 || help) return parsed;
  // Before any subcommand starts a worker thread, so that every thread runs with it.
  caustica::cli::install_interrupt_handler();
  caustica::cli::set_interrupt_messages(ranks->is_root());
  for (auto& [sub, run] : runners)
    if (sub->parsed()) {
      try {
        return run(*ranks);
      } catch (const std::exception& e) {
        caustica::cli::print_error(e.what());
        // The other ranks may be waiting in a collective this rank will never join.
        if (ranks->size() > 1) ranks->abort(1);
        return 1;
      }
    }
  return 2;
}
