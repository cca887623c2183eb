#include "scene_setup.h"

#include <chrono>
#include <cstdint>
#include <limits>
#include <string>

#include "integrators/bidir/mis.h"
#include "io/scene_loader.h"
#include "preflight.h"

namespace caustica::cli {

namespace {

// Path guiding (guided-pt): src/guiding/guiding_settings.h has the meaning of each.
void add_guiding_options(CheckedOptions& o, SharedOptions* s) {
  o.number("--guiding-spatial-threshold", &s->guiding.spatial_threshold, 0, 1e12, true,
           "Guiding: split a spatial leaf after c sqrt(2^k) path vertices in training pass k "
           "(default 4000; Mueller 2017: 12000)");
  o.number("--guiding-rho", &s->guiding.rho, 0, 1, true,
           "Guiding: refine a directional quadrant holding more than this share of the energy "
           "(default 0.05; Mueller 2017: 0.01)");
  o.number("--guiding-carry", &s->guiding.carry, 0, 1, false,
           "Guiding: share of a spatial leaf's learned energy that the next training pass starts "
           "from, 0..1 (default 0.5; 0: each pass learns from its own samples alone, as Mueller "
           "2017)");
  o.integer("--guiding-max-mb", &s->guiding_max_mb, 1, 65536,
            "Guiding: memory cap of the learned structure in MiB (default 32)");
  o.number("--guiding-bsdf-fraction", &s->guiding.bsdf_fraction, 0, 1, true,
           "Guiding: fixed probability in (0, 1] of sampling the BSDF instead of the learned "
           "distribution (default: learned per spatial leaf by Adam, Mueller 2019)");
  o.number("--guiding-nee-floor", &s->guiding.nee_floor, 0, 1, true,
           "Guiding: probability in (0, 1] of next event estimation at vertices whose spatial "
           "leaf took 64 or more light samples in a training pass and saw no light; guided-bpt "
           "and guided-vcm also of lens connections that saw nothing and of connections of which "
           "at most 5% were unoccluded, in their MIS weights (default 0.25; 1: every technique "
           "at every vertex, as Mueller 2017 and bpt/vcm)");
  o.choice("--guiding-filter", &s->guiding_filter, {"on", "off"},
           "Guiding: box-filtered splatting into the spatial and directional trees, on or off "
           "(default on)");
  o.choice("--guiding-target", &s->guiding_target, {"cosine", "radiance"},
           "Guiding (guided-pt): what the directional distributions learn, incident radiance "
           "times the cosine to the surface (a product with the cosine) or radiance alone as "
           "Mueller 2017 (default cosine)");
  o.choice("--guiding-subpaths", &s->guiding_subpaths, {"both", "camera", "light"},
           "Guiding (guided-bpt, guided-vcm): guide both subpaths, or only camera subpaths (by "
           "learned radiance) or only light subpaths (by learned importance) (default both)");
  o.choice("--guiding-radiance", &s->guiding_radiance, {"photons", "camera", "both"},
           "Guiding (guided-bpt, guided-vcm): what the radiance that guides camera subpaths is "
           "learned from: the light vertices (photons), the radiance the camera subpaths' own "
           "vertices received through every technique (as guided-pt), or both (default camera)");
  o.choice("--guiding-importance", &s->guiding_importance, {"importons", "light", "both"},
           "Guiding (guided-bpt, guided-vcm): what the importance that guides light subpaths is "
           "learned from: the camera vertices (importons), what the light subpaths' own later "
           "vertices saw of the lens, or both (default light)");
  o.choice("--guiding-mis", &s->guiding_mis, {"mixture", "bsdf"},
           "Guiding (guided-bpt, guided-vcm): MIS weights from the guided mixtures' densities "
           "or from the BSDFs' alone, as unguided bpt/vcm (both unbiased; default bsdf: no guide "
           "densities outside sampling)");
  o.choice("--guiding-combine", &s->guiding_combine, {"inverse-variance", "equal"},
           "Guiding (guided-pt, guided-bpt, guided-vcm): weight the passes in the image by "
           "inverse variance, or every iteration equally (default inverse-variance)");
}

}  // namespace

CLI::Option* add_shared_options(CheckedOptions& o, SharedOptions* s, const std::string& time_help) {
  CLI::Option* time =
      o.number("--time", &s->seconds, 0, kMaxSeconds, true, time_help + ", at most 30 days");
  o.integer("--threads", &s->threads, 0, 1024, "Worker threads, 0..1024 (default 0: all cores)");
  // Light vertices store their depth in 8 bits, hence 255.
  o.integer("--max-depth", &s->max_depth, 0, 255,
            "Maximum scattering vertices, 0..255 (pbrt-v4 maxdepth; 1 = direct light; default: the "
            "scene's, else 10)");
  o.integer("--seed", &s->seed, uint64_t(0), std::numeric_limits<uint64_t>::max(),
            "Random seed (default 0)");
  o.resolution("--resolution", &s->width, &s->height,
               "Override the film resolution, WxH (must fit in memory)");
  o.choice("--mis", &s->mis, {"balance", "power"},
           "MIS heuristic: balance or power (default: each integrator's own; `caustica "
           "integrators` lists them)");
  o.integer("--camera", &s->camera, 0, std::numeric_limits<int>::max(),
            "glTF: which camera to use, in node order (default: the first)");
  o.integer(
      "--light-paths", &s->bidir.light_paths, uint64_t(1), kMaxLightPaths,
      "Bidirectional: light subpaths per iteration (default: pixel count); at most 2^31-2, as the "
      "integrators index paths with 32 bits, and at most what memory holds at 40 bytes per path");
  o.number("--radius", &s->bidir.radius, 0, 1e12, true,
           "Photon mapping / VCM: initial merge radius, positive, at most 1e12 so that pi r^2 "
           "times the light paths stays a finite float (default: from scene size)");
  o.number("--radius-alpha", &s->bidir.radius_alpha, 0, 1, true,
           "Photon mapping / VCM: radius reduction alpha in (0, 1] (default 0.75)");
  o.text("--techniques", &s->bidir.techniques_dir,
         "Bidirectional: write one weighted image per technique to DIR");
  o.integer("--connections", &s->bidir.connections, 1, 64,
            "bpt / vcm: light subpaths each camera vertex connects to, 1..64 (default 1)");
  o.number("--merge-mis-scale", &s->bidir.merge_mis_scale, 0, 100, true,
           "vcm / guided-vcm: factor of the merges' sample count N pi r^2 in the MIS weights "
           "only, in (0, 100] (default 1: the balance heuristic of Georgiev et al. 2012; below 1 "
           "trusts merging less; the weights still sum to one; adaptive-vcm keeps 1)");
  o.choice("--merge-mis", &s->merge_mis, {"balance", "correlation-aware"},
           "vcm: the merges' MIS weights: the balance heuristic's count N pi r^2 (default), or "
           "that count lowered per merge by the correlation of the paths that share its light "
           "subpath (Grittmann et al. 2021; --max-depth at most 128)");
  o.choice("--adaptive-costs", &s->adaptive_costs, {"model", "measured"},
           "adaptive-vcm: price techniques with the fixed cost model (default; deterministic) or "
           "with costs measured on this machine while rendering (not reproducible)");
  add_guiding_options(o, s);
  return time;
}

namespace {

int check_before_loading(const SceneSetup& s) {
  std::string problem = scene_path_problem(s.scene);
  if (problem.empty() && s.width > 0)
    problem = film_memory_problem(s.width, s.height, s.bidir.light_paths);
  if (problem.empty()) return 0;
  print_error(problem);
  return 2;
}

}  // namespace

int load_configured_scene(const SceneSetup& s, std::unique_ptr<Scene>* scene,
                          IntegratorSettings* settings, double* load_seconds) {
  if (int rc = check_before_loading(s)) return rc;
  const auto start = std::chrono::steady_clock::now();
  try {
    LoadOptions load;
    load.camera_index = s.camera;
    *scene = load_scene(s.scene, load);
  } catch (const UnknownSceneError& e) {
    print_error(e.what());  // quotes the user's name: keep it one line
    return 2;
  } catch (const SceneLoadError& e) {
    std::fprintf(stderr, "%s\n", e.what());
    return 2;
  }
  if (load_seconds)
    *load_seconds = std::chrono::duration<double>(std::chrono::steady_clock::now() - start).count();
  if (s.width > 0) (*scene)->override_resolution(s.width, s.height);
  // The scene file's own resolution has not been checked yet.
  const std::string problem = film_memory_problem((*scene)->camera().width(),
                                                  (*scene)->camera().height(), s.bidir.light_paths);
  if (!problem.empty()) {
    print_error(problem);
    return 2;
  }
  const int scene_depth = (*scene)->settings().max_depth;
  settings->max_depth = s.max_depth >= 0 ? s.max_depth : (scene_depth > 0 ? scene_depth : 10);
  settings->seed = s.seed;
  if (!s.mis.empty())
    settings->mis = s.mis == "balance" ? MisHeuristic::Balance : MisHeuristic::Power;
  settings->bidir = s.bidir;
  settings->bidir.measured_costs = s.adaptive_costs == "measured";
  settings->bidir.correlation_aware = s.merge_mis == "correlation-aware";
  if (settings->bidir.correlation_aware &&
      settings->max_depth > bidir::CorrelationTrack::kMaxEntries) {
    print_error("--merge-mis correlation-aware supports a maximum depth of at most " +
                std::to_string(bidir::CorrelationTrack::kMaxEntries) + ", not " +
                std::to_string(settings->max_depth) + " (give --max-depth)");
    return 2;
  }
  settings->guiding = s.guiding;
  settings->guiding.max_bytes = size_t(s.guiding_max_mb) << 20;
  settings->guiding.filter = s.guiding_filter == "on";
  settings->guiding.cosine_product = s.guiding_target == "cosine";
  settings->guiding.inverse_variance = s.guiding_combine == "inverse-variance";
  settings->guiding.guide_camera_paths = s.guiding_subpaths != "light";
  settings->guiding.guide_light_paths = s.guiding_subpaths != "camera";
  settings->guiding.guided_mis = s.guiding_mis == "mixture";
  using Records = GuidingSettings::RadianceRecords;
  settings->guiding.radiance_records = s.guiding_radiance == "camera" ? Records::CameraPaths
                                       : s.guiding_radiance == "both" ? Records::Both
                                                                      : Records::Photons;
  using Importance = GuidingSettings::ImportanceRecords;
  settings->guiding.importance_records = s.guiding_importance == "light"  ? Importance::LightPaths
                                         : s.guiding_importance == "both" ? Importance::Both
                                                                          : Importance::Importons;
  return 0;
}

}  // namespace caustica::cli
