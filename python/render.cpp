// render(), compare() and integrators() of the Python module: the command line's `render` and
// `compare` (apps/caustica/cmd_render.cpp, cmd_compare.cpp) with keyword arguments for flags.
#include <pybind11/stl.h>
#include <tbb/global_control.h>
#include <tbb/info.h>

#include <atomic>
#include <chrono>
#include <future>
#include <limits>
#include <sstream>
#include <thread>

#include "bindings.h"
#include "experiment/comparison.h"
#include "experiment/report.h"
#include "integrators/registry.h"
#include "preflight.h"
#include "render/renderer.h"
#include "scene_setup.h"

namespace caustica::python {

namespace {

using namespace std::chrono_literals;

std::string join(const std::vector<std::string>& items) {
  std::string out;
  for (const auto& s : items) out += (out.empty() ? "" : ", ") + s;
  return out;
}

void check_integrator(const std::string& name) {
  const std::vector<std::string> names = integrator_names();
  if (std::find(names.begin(), names.end(), name) == names.end())
    throw py::value_error("unknown integrator '" + name + "'; valid: " + join(names));
}

// The integrator options render() and compare() take as keywords, named as the command line's
// flags without dashes (--light-paths: light_paths), with the same ranges. None means not given.
IntegratorSettings integrator_settings(const LoadedScene& s, uint64_t seed,
                                       const py::kwargs& options) {
  IntegratorSettings settings;
  const int scene_depth = s.scene->settings().max_depth;
  settings.max_depth = s.max_depth >= 0 ? s.max_depth : (scene_depth > 0 ? scene_depth : 10);
  settings.seed = seed;
  for (const auto& [key, value] : options) {
    const std::string name = py::str(key);
    if (value.is_none()) continue;
    if (name == "mis") {
      const std::string mis = py::isinstance<py::str>(value) ? value.cast<std::string>() : "";
      if (mis != "balance" && mis != "power")
        throw py::value_error("mis must be one of balance, power, got " +
                              std::string(py::repr(value)));
      settings.mis = mis == "balance" ? MisHeuristic::Balance : MisHeuristic::Power;
    } else if (name == "max_depth") {
      // Light vertices store their depth in 8 bits, hence 255.
      settings.max_depth = int(integer_arg(name, value, 0, 255));
    } else if (name == "light_paths") {
      // The integrators index light paths with 32 bits.
      settings.bidir.light_paths = unsigned_arg(name, value, 1, cli::kMaxLightPaths);
    } else if (name == "radius") {
      // At most 1e12, so that pi r^2 times the light paths stays a finite float.
      settings.bidir.radius = float(number_arg(name, value, 0, 1e12, true));
    } else if (name == "radius_alpha") {
      settings.bidir.radius_alpha = float(number_arg(name, value, 0, 1, true));
    } else if (name == "connections") {
      settings.bidir.connections = int(integer_arg(name, value, 1, 64));
    } else if (name == "merge_mis_scale") {
      settings.bidir.merge_mis_scale = float(number_arg(name, value, 0, 100, true));
    } else if (name == "adaptive_costs") {
      const std::string c = py::isinstance<py::str>(value) ? value.cast<std::string>() : "";
      if (c != "model" && c != "measured")
        throw py::value_error("adaptive_costs must be one of model, measured, got " +
                              std::string(py::repr(value)));
      settings.bidir.measured_costs = c == "measured";
    } else {
      throw py::value_error("unknown option '" + name +
                            "'; valid: mis, max_depth, light_paths, radius, radius_alpha, "
                            "connections, merge_mis_scale, adaptive_costs");
    }
  }
  const Camera& camera = s.scene->camera();
  if (std::string problem =
          cli::film_memory_problem(camera.width(), camera.height(), settings.bidir.light_paths);
      !problem.empty())
    throw py::value_error(problem);
  return settings;
}

int thread_count(const py::handle& threads) {
  const int n = int(integer_arg("threads", threads, 0, 1024));
  return n > 0 ? n : tbb::info::default_concurrency();
}

// Runs `work` on a thread of its own while the calling thread, without the GIL, wakes every
// 50 ms to let Python handle signals. Python runs signal handlers only in its main thread, and
// only when that thread executes Python code, so a render on the calling thread could not be
// interrupted. When a handler raises (Ctrl-C: KeyboardInterrupt), `stop` asks the work to end
// after its current iteration, and the handler's exception is raised here once it has.
template <typename Work>
auto run_interruptibly(std::atomic<bool>* stop, Work work) -> decltype(work()) {
  using Result = decltype(work());
  std::packaged_task<Result()> task(std::move(work));
  std::future<Result> done = task.get_future();
  bool signalled = false;
  {
    py::gil_scoped_release release;
    std::thread worker(std::move(task));
    while (done.wait_for(50ms) != std::future_status::ready) {
      if (signalled) continue;
      py::gil_scoped_acquire acquire;
      if (PyErr_CheckSignals() != 0) {
        signalled = true;
        stop->store(true);
      }
    }
    worker.join();
  }
  if (signalled) throw py::error_already_set();  // the handler's exception, still pending
  return done.get();                             // the work's own exception, if any
}

py::array_t<float> render_scene(const LoadedScene& s, const std::string& integrator_name,
                                const py::object& spp, const py::object& time,
                                const py::object& seed, const py::object& threads,
                                const py::kwargs& options) {
  check_integrator(integrator_name);
  const IntegratorSettings settings = integrator_settings(
      s, unsigned_arg("seed", seed, 0, std::numeric_limits<uint64_t>::max()), options);
  RenderBudget budget;
  if (!spp.is_none()) budget.spp = int(integer_arg("spp", spp, 1, std::numeric_limits<int>::max()));
  if (!time.is_none()) budget.seconds = number_arg("time", time, 0, cli::kMaxSeconds, true);
  if (budget.spp == 0 && budget.seconds == 0)
    budget.spp = s.scene->settings().spp > 0 ? s.scene->settings().spp : 16;
  const int n_threads = thread_count(threads);

  auto integrator = make_integrator(integrator_name, settings);
  std::atomic<bool> stop{false};
  RenderCallbacks callbacks;
  callbacks.quiet = true;  // a progress bar on stderr is noise in a notebook
  callbacks.stop = &stop;
  tbb::global_control limit(tbb::global_control::max_allowed_parallelism, size_t(n_threads));
  const RenderResult result =
      run_interruptibly(&stop, [&] { return render(*s.scene, *integrator, budget, callbacks); });
  return to_array(result.image);
}

std::vector<std::string> integrator_list(const py::handle& integrators) {
  std::vector<std::string> names;
  if (py::isinstance<py::str>(integrators)) {  // "pt,vcm", as --integrators
    std::stringstream list(integrators.cast<std::string>());
    for (std::string item; std::getline(list, item, ',');)
      if (!item.empty()) names.push_back(item);
  } else {
    for (const py::handle item : integrators) {
      if (!py::isinstance<py::str>(item))
        throw py::type_error("integrators must be names (str), got " + std::string(py::repr(item)));
      names.push_back(item.cast<std::string>());
    }
  }
  if (names.empty()) throw py::value_error("integrators is empty");
  for (const auto& n : names) check_integrator(n);
  return names;
}

py::object compare(const LoadedScene& s, const py::object& integrators, const py::object& time,
                   const py::object& reference_array, const py::object& threads,
                   const py::object& seed, const py::object& runs, const py::kwargs& options) {
  ComparisonConfig config;
  config.integrators = integrator_list(integrators);
  config.seconds = number_arg("time", time, 0, cli::kMaxSeconds, true);
  config.runs = int(integer_arg("runs", runs, 1, 1000));
  config.settings = integrator_settings(
      s, unsigned_arg("seed", seed, 0, std::numeric_limits<uint64_t>::max()), options);
  config.threads = thread_count(threads);
  const int width = s.scene->camera().width(), height = s.scene->camera().height();
  Image reference;
  std::string reference_description;
  if (!reference_array.is_none()) {
    reference = to_image(reference_array, "reference");
    if (reference.width() != width || reference.height() != height)
      throw py::value_error("reference is " + std::to_string(reference.width()) + "x" +
                            std::to_string(reference.height()) + " but the scene renders " +
                            std::to_string(width) + "x" + std::to_string(height) +
                            " (see load()'s resolution)");
    reference_description = "an array given to caustica.compare";
  }

  std::atomic<bool> stop{false};
  config.stop = &stop;
  ComparisonResult result = run_interruptibly(&stop, [&] {
    if (reference.empty()) {
      // As the command line: no reference given, so render one first with the most robust
      // integrator for 4x the per-integrator time, with noise independent of the compared runs.
      std::string ref_integrator = "pt";
      for (const auto& n : integrator_names())
        if (n == "vcm") ref_integrator = "vcm";
      IntegratorSettings ref_settings = config.settings;
      ref_settings.seed = config.settings.seed + 7919;
      auto integrator = make_integrator(ref_integrator, ref_settings);
      RenderBudget budget;
      budget.seconds = 4 * config.seconds;
      RenderCallbacks callbacks;
      callbacks.quiet = true;
      callbacks.stop = &stop;
      tbb::global_control limit(tbb::global_control::max_allowed_parallelism,
                                size_t(config.threads));
      const RenderResult r = render(*s.scene, *integrator, budget, callbacks);
      if (r.interrupted) return ComparisonResult{};  // the caller raises KeyboardInterrupt
      reference = r.image;
      std::ostringstream d;
      d << ref_integrator << ", " << r.iterations << " iterations, " << int(r.seconds + 0.5)
        << " s, rendered by compare";
      reference_description = d.str();
    }
    return run_comparison(*s.scene, reference, config);
  });
  result.scene = s.name_or_path;
  result.reference_description = reference_description;
  // Through JSON text, so the dict is exactly what a reader of results.json gets.
  return py::module_::import("json").attr("loads")(comparison_json(result).dump());
}

}  // namespace

void add_render_functions(py::module_& m) {
  m.def(
      "integrators",
      [] {
        py::dict out;  // insertion-ordered: the registry's (and the README's) order
        for (const IntegratorInfo& info : integrator_registry())
          out[py::str(info.name)] = info.description;
        return out;
      },
      "integrators() -> dict name -> one-line description: the integrators render() and compare() "
      "accept, from the registry, in the order the README documents them.");

  m.def(
      "render", &render_scene, py::arg("scene"), py::arg("integrator") = kDefaultIntegrator,
      py::arg("spp") = py::none(), py::arg("time") = py::none(), py::arg("seed") = 0,
      py::arg("threads") = 0,
      "render(scene, integrator='adaptive-vcm', spp=None, time=None, seed=0, threads=0, **options)"
      " -> numpy.ndarray float32 (height, width, 3), linear RGB\n\n"
      "Renders as `caustica render` does, and with the same settings to the same bits.\n"
      "spp: iterations (samples per pixel), >= 1; time: seconds, at most 30 days; both: "
      "whichever ends first; neither: the scene's spp, else 16.\n"
      "seed: 0..2^64-1. threads: 0..1024, 0 = all cores (the image does not depend on it).\n"
      "options, as the command line's flags: mis ('balance' or 'power'; default: power for pt, "
      "balance for the bidirectional family), max_depth (0..255; default: the scene's), "
      "light_paths (light subpaths per iteration, >= 1; default: one per pixel), radius "
      "(initial merge radius, > 0; default: from the scene size), radius_alpha (in (0, 1]; "
      "default 0.75), connections (light subpaths per camera vertex for bpt/vcm, 1..64), "
      "merge_mis_scale (the merges' count in the vcm/guided-vcm MIS weights, in (0, 100]; "
      "default 1), adaptive_costs ('model' or 'measured', adaptive-vcm). None means not given. "
      "Unknown names "
      "or bad values raise ValueError.\n"
      "Releases the GIL; Ctrl-C ends the render after its current iteration and raises "
      "KeyboardInterrupt.");

  m.def("compare", &compare, py::arg("scene"), py::arg("integrators"), py::arg("time"),
        py::arg("reference") = py::none(), py::arg("threads") = 0, py::arg("seed") = 0,
        py::arg("runs") = 1,
        "compare(scene, integrators, time, reference=None, threads=0, seed=0, runs=1, **options) "
        "-> dict"
        "\n\nEqual-time comparison as `caustica compare`: each integrator (a list of names, or "
        "'pt,vcm') renders for `time` seconds, and its errors against the reference are taken "
        "at 1, 2, 4, ... s and at the end. reference: an array of the scene's size, or None to "
        "render one first with vcm for 4x time (seed + 7919), as the command line does. runs: "
        "1..1000 runs per integrator with seeds seed, seed + 1, ..., taking turns (as --runs); "
        "each integrator's summary row and run are then its median run by relMSE, with every "
        "run's errors in the row's relmse_runs and the run's repeats. options "
        "as for render(). Returns the content of the report's results.json: scene, "
        "seconds_per_integrator, threads, reference, interrupted, summary (final errors and "
        "speed-up vs pt per integrator) and runs (every snapshot). Ctrl-C raises "
        "KeyboardInterrupt.");
}

}  // namespace caustica::python
