#include "scene_setup.h"

#include <chrono>
#include <cstdio>

#include "commands.h"
#include "io/scene_loader.h"

namespace caustica::cli {

int load_configured_scene(const SceneSetup& s, std::unique_ptr<Scene>* scene,
                          IntegratorSettings* settings, double* load_seconds) {
  if (!s.mis.empty() && !check_name("MIS heuristic", s.mis, {"balance", "power"})) return 2;
  int w = 0, h = 0;
  if (!s.resolution.empty() &&
      (std::sscanf(s.resolution.c_str(), "%dx%d", &w, &h) != 2 || w <= 0 || h <= 0)) {
    std::fprintf(stderr, "caustica: error: --resolution expects WxH, e.g. 256x256, got '%s'\n",
                 s.resolution.c_str());
    return 2;
  }
  const auto start = std::chrono::steady_clock::now();
  try {
    LoadOptions load;
    load.camera_index = s.camera;
    *scene = load_scene(s.scene, load);
  } catch (const UnknownSceneError& e) {
    std::fprintf(stderr, "caustica: error: %s\n", e.what());
    return 2;
  } catch (const SceneLoadError& e) {
    std::fprintf(stderr, "%s\n", e.what());
    return 2;
  }
  if (load_seconds)
    *load_seconds = std::chrono::duration<double>(std::chrono::steady_clock::now() - start).count();
  if (w > 0) (*scene)->override_resolution(w, h);
  const int scene_depth = (*scene)->settings().max_depth;
  settings->max_depth = s.max_depth >= 0 ? s.max_depth : (scene_depth > 0 ? scene_depth : 10);
  settings->seed = s.seed;
  settings->mis = s.mis == "balance" ? MisHeuristic::Balance : MisHeuristic::Power;
  settings->mis_from_user = !s.mis.empty();
  return 0;
}

}  // namespace caustica::cli
