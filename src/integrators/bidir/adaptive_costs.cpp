#include "integrators/bidir/adaptive_costs.h"

#include <algorithm>

namespace caustica::bidir {

namespace {
double query_price(const AdaptivePlan::Candidate& c, const CostModel& t) {
  return t.merge_query * std::max(1.0, double(c.light_path_factor));
}
}  // namespace

CostModel costs_of(const ProbeWork& w, bool measured) {
  CostModel t;
  if (!measured) return t;
  auto per = [](double seconds, double count, double fallback) {
    return count > 0 && seconds > 0 ? 1e6 * seconds / count : fallback;
  };
  const double own_camera = w.camera_seconds - w.connect_seconds - w.merge_seconds;
  t.camera_vertex = per(own_camera, w.camera_vertices, t.camera_vertex);
  // Probes run the core only: pt's vertex is priced at the model's ratio to the core's.
  t.path_tracing_vertex =
      t.camera_vertex * (CostModel{}.path_tracing_vertex / CostModel{}.camera_vertex);
  // The probes' light passes connect to the lens where a pixel takes splats: timed together,
  // split in the model's proportion.
  const CostModel fixed;
  const double model_light = w.light_paths * fixed.light_path +
                             w.light_vertices * (fixed.light_vertex + fixed.lens_connection);
  if (model_light > 0 && w.light_seconds > 0) {
    const double scale = 1e6 * w.light_seconds / model_light;
    t.light_path *= scale;
    t.light_vertex *= scale;
    t.lens_connection *= scale;
  }
  // A probe's connections are half to the pixel's own light path, half to random ones, timed
  // together: split in the model's proportion.
  const double own = CostModel{}.own_connection / CostModel{}.connection;
  if (w.connections > 0 && w.connect_seconds > 0) {
    t.connection = per(w.connect_seconds, w.connections, t.connection) * 2.0 / (1.0 + own);
    t.own_connection = own * t.connection;
  }
  // Queries and photons share one clock: split it in the model's proportion.
  const double model = w.merge_queries * t.merge_query + w.photons * t.photon;
  if (model > 0 && w.merge_seconds > 0) {
    const double scale = 1e6 * w.merge_seconds / model;
    t.merge_query *= scale;
    t.photon *= scale;
  }
  return t;
}

nlohmann::json to_json(const CostModel& t) {
  return {{"camera_vertex", t.camera_vertex},
          {"path_tracing_vertex", t.path_tracing_vertex},
          {"light_path", t.light_path},
          {"light_vertex", t.light_vertex},
          {"lens_connection", t.lens_connection},
          {"connection", t.connection},
          {"own_connection", t.own_connection},
          {"merge_query", t.merge_query},
          {"photon", t.photon}};
}

PixelWork pixel_work_of(const ProbeWork& w, double probes, double pixels, int probe_connections) {
  return {w.camera_vertices / (probes * pixels),
          w.connections / (probes * pixels * probe_connections),
          w.light_paths > 0 ? w.light_vertices / w.light_paths : 0.0,
          w.merge_queries / (probes * pixels),
          w.photons / (probes * pixels),
          w.stop_camera_vertices / (probes * pixels),
          w.stop_merge_queries / (probes * pixels),
          w.stop_photons / (probes * pixels)};
}

double light_path_cost(const PixelWork& w, const CostModel& t, bool splats) {
  return t.light_path +
         w.light_vertices_per_path * (t.light_vertex + (splats ? t.lens_connection : 0.0));
}

double light_cost(const AdaptivePlan::Candidate& c, const PixelWork& w, const CostModel& t,
                  bool splats) {
  return c.light_path_factor * light_path_cost(w, t, splats);
}

double path_tracing_cost(const AdaptivePlan::Candidate& c, const PixelWork& w, const CostModel& t) {
  return w.camera_vertices * t.path_tracing_vertex + light_cost(c, w, t, false);
}

double base_cost(const AdaptivePlan::Candidate& c, const PixelWork& w, const CostModel& t) {
  if (c.light_path_factor == 0) return path_tracing_cost(c, w, t);
  const double connections =
      c.connections > 0 ? t.own_connection + (c.connections - 1) * t.connection : 0.0;
  return w.camera_vertices * t.camera_vertex + light_cost(c, w, t, true) +
         w.connections * connections;
}

double merge_cost(const AdaptivePlan::Candidate& c, const PixelWork& w, const CostModel& t) {
  return w.merge_queries * query_price(c, t) + w.photons * c.light_path_factor * t.photon;
}

double stop_cost(const AdaptivePlan::Candidate& c, const PixelWork& w, const CostModel& t) {
  return w.stop_camera_vertices * t.path_tracing_vertex + w.stop_merge_queries * query_price(c, t) +
         w.stop_photons * c.light_path_factor * t.photon + light_cost(c, w, t, false);
}

}  // namespace caustica::bidir
