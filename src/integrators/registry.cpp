#include "integrators/registry.h"

#include "integrators/bidir/bidir_integrator.h"
#include "integrators/guided_path_tracer.h"
#include "integrators/path_tracer.h"

namespace caustica {

namespace {

std::function<std::unique_ptr<Integrator>(const IntegratorSettings&)> bidir(BidirAlgorithm a) {
  return [a](const IntegratorSettings& s) { return make_bidir_integrator(a, s); };
}

std::vector<IntegratorInfo> make_registry() {
  std::vector<IntegratorInfo> r;
  r.push_back({"pt", "path tracing: BSDF sampling and next event estimation with MIS", true, true,
               false, MisHeuristic::Power,
               [](const IntegratorSettings& s) { return std::make_unique<PathTracer>(s); }});
  r.push_back({"lt", "light tracing: light subpaths splatted to the camera", true, true, false,
               MisHeuristic::Balance, bidir(BidirAlgorithm::LightTracing)});
  r.push_back({"bpt", "bidirectional path tracing: every connection, MIS over all techniques", true,
               true, false, MisHeuristic::Balance, bidir(BidirAlgorithm::Bpt)});
  r.push_back({"ppm",
               "progressive photon mapping: camera paths merge at their first diffuse vertex",
               false, true, true, MisHeuristic::Balance, bidir(BidirAlgorithm::Ppm)});
  r.push_back({"bpm", "bidirectional photon mapping: merging at every camera vertex, MIS", false,
               true, true, MisHeuristic::Balance, bidir(BidirAlgorithm::Bpm)});
  r.push_back({"vcm", "vertex connection and merging: bpt and bpm under one MIS", false, true, true,
               MisHeuristic::Balance, bidir(BidirAlgorithm::Vcm)});
  r.push_back({"adaptive-vcm",
               "vcm that picks its light paths, connections and, per pixel, path tracing or "
               "merging while rendering (efficiency-aware MIS, Grittmann 2022)",
               false, true, true, MisHeuristic::Balance, bidir(BidirAlgorithm::AdaptiveVcm)});
  r.push_back({"guided-pt",
               "path tracing guided by incident radiance learned while rendering (Mueller 2017)",
               true, true, false, MisHeuristic::Power,
               [](const IntegratorSettings& s) { return std::make_unique<GuidedPathTracer>(s); }});
  r.push_back({"guided-bpt",
               "bpt with camera subpaths guided by radiance and light subpaths by importance, "
               "both learned from the guided subpaths (Mueller 2017, Vorba 2014)",
               true, true, false, MisHeuristic::Balance, bidir(BidirAlgorithm::GuidedBpt)});
  r.push_back({"guided-vcm", "vcm with the guided subpaths of guided-bpt", false, true, true,
               MisHeuristic::Balance, bidir(BidirAlgorithm::GuidedVcm)});
  return r;
}

}  // namespace

const std::vector<IntegratorInfo>& integrator_registry() {
  static const std::vector<IntegratorInfo> registry = make_registry();
  return registry;
}

const IntegratorInfo* find_integrator(const std::string& name) {
  for (const IntegratorInfo& info : integrator_registry())
    if (info.name == name) return &info;
  return nullptr;
}

std::vector<std::string> integrator_names() {
  std::vector<std::string> names;
  for (const IntegratorInfo& info : integrator_registry()) names.push_back(info.name);
  return names;
}

std::unique_ptr<Integrator> make_integrator(const std::string& name,
                                            const IntegratorSettings& settings) {
  const IntegratorInfo* info = find_integrator(name);
  if (!info) return nullptr;
  IntegratorSettings s = settings;
  if (!s.mis) s.mis = info->default_mis;
  return info->make(s);
}

}  // namespace caustica
