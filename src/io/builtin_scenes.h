// Scenes built in code, reachable by name (`--scene NAME`). `cornell-glass` is the embedded
// default and is identical to scenes/cornell-caustics.pbrt.
#pragma once

#include <memory>
#include <string>
#include <vector>

#include "scene/scene.h"

namespace caustica {

struct BuiltinSceneInfo {
  std::string name;
  std::string description;
};

std::vector<BuiltinSceneInfo> builtin_scenes();
inline const char* default_scene_name() { return "cornell-glass"; }

// Returns nullptr for an unknown name. `width`/`height` > 0 override the resolution.
std::unique_ptr<Scene> make_builtin_scene(const std::string& name, int width = 0, int height = 0);

// Parameters of the analytic furnace scenes (tests read them to know the exact answer).
struct FurnaceParams {
  float albedo = 0.5f;
  float emission = 1.f;
  // Radiance everywhere inside: Le / (1 - albedo).
  float expected_radiance() const { return emission / (1.f - albedo); }
};
std::unique_ptr<Scene> make_furnace_scene(const FurnaceParams& params, int width = 32,
                                          int height = 32);

}  // namespace caustica
