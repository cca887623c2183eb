#include "integrators/bidir/adaptive_plan.h"

#include <tbb/parallel_for.h>

#include <algorithm>
#include <cassert>
#include <cmath>
#include <limits>
#include <nlohmann/json.hpp>

#include "core/compact_float.h"
#include "core/math.h"
#include "integrators/bidir/grid_statistics.h"

namespace caustica::bidir {

namespace {
// The fixed cost model, in microseconds per operation: a least-squares fit of camera-pass and
// light-pass times to the operation counts (statistics "work_per_iteration") of vcm and bpt at
// 1 and 4 connections and 0.25-2 light paths per pixel on door-ajar, cornell-box, veach-bidir
// and water-caustic (1 thread, 2-core x86-64, g++ 12 Release, 2026-11-30; per scene the camera
// vertex ranged 0.6-1.0 us, a connection 0.5-0.7, a light vertex 0.8-2.0). Scenes whose BSDFs
// are expensive to evaluate (coated materials: material-testball fits 2.9 / 8.6 / 4.4) are
// mispriced; --adaptive-costs measured times the probes instead. Used whenever costs are not
// measured, so that a render at fixed spp and seed chooses the same configurations on every
// machine and for every thread count.
struct CostModel {
  double camera_vertex = 0.75;  // trace, BSDF, NEE with its shadow ray
  // A camera vertex of a path-tracing iteration, which pt's own estimator renders (no MIS sums
  // for other techniques): fitted so that the predicted bpt / pt cost ratio matches the
  // measured one (1 thread, 160 px wide, 16 spp, 2026-11-30: door-ajar 5.3, cornell-box 4.1,
  // veach-bidir 5.0, mis-plates 1.75, coffee 2.7; at 0.75 the model predicted 1.25x less).
  double path_tracing_vertex = 0.6;
  double light_vertex = 1.1;  // trace, BSDF, store, connect to the lens
  // One light vertex connected to one camera vertex: of a light path drawn at random, and of
  // the pixel's own light path, which costs less. The fit above had one connection, the
  // pixel's own, and four: its slope is the random ones'. Measured 2026-12-04 (door-ajar
  // 160 x 120, 2 threads, adaptive-vcm's core at fixed configurations, thread-microseconds per
  // pixel and iteration from "checks"): 1, 2, 4 connections at one light path per pixel 5.88,
  // 8.78, 14.19, none 3.81, so the first 0.32 us, each further one 0.42-0.45, against a
  // camera vertex of 0.54 (0.45 and 0.6 at this model's 0.75). Priced alike, the model
  // preferred two connections, or none, to one (door-ajar: 1.18x bpt's relMSE over 4 seeds).
  double connection = 0.6;
  double own_connection = 0.45;
  // One range query at up to one light path per pixel; above that its price grows with the
  // light paths (query_price): the grid and the vertices it points to outgrow the caches.
  // door-ajar, as above: a query, the grid's build shared among them included, took 0.19 us
  // at one light path per pixel and 0.43 at two, beside a camera vertex of 0.54 (0.26 and 0.6
  // at this model's 0.75; the fit above gave 0.18, which priced merging at two light paths
  // per pixel at half of what it took).
  double merge_query = 0.25;
  double photon = 0.03;  // one photon gathered
};

double query_price(const AdaptivePlan::Candidate& c, const CostModel& t) {
  return t.merge_query * std::max(1.0, double(c.light_path_factor));
}
constexpr float kLightPathFactors[] = {0.25f, 0.5f, 1.f, 2.f};
constexpr int kConnections[] = {0, 1, 2, 4, 8};
constexpr double kRelEps = 0.01;      // as the relMSE metric (image/metrics.h)
constexpr int kBlurRadius = 3;        // pixel variances pooled over 7 x 7 (box_blur)
constexpr double kWinsorize = 0.995;  // quantile of pixel variances kept (relative_variances)
// Path tracing is kept unless another configuration's predicted relVar x time is lower by more
// than this factor. The cost model has no term for the per-iteration costs of light paths (their
// pipeline, the splats), and the predicted variances carry a few percent of noise: on mis-plates
// a quarter of the light paths won by 0.25% of the score while `pt` was 1.09x (20 s) and 1.15x
// (60 s) better. The margin changes no choice where a configuration is predicted 5% better.
constexpr double kPathTracingMargin = 1.05;
// A pixel path traces alone only where its predicted variance is at most this much above the
// core's: the prediction is that of path tracing under the balance heuristic (the candidate
// without light paths) while pt's estimator uses the power heuristic, and a pixel's rare bright
// paths are the least predictable part. 20 s, 1 thread, seeds 0 / 1, relMSE: veach-mis without
// the bound 0.000696 / 0.000692, with 1.0 0.000620 / 0.000584, with 1.1 0.000684 / 0.000643
// (before pixels could path trace: 0.000666 / 0.000622); sun-glass 0.000339 / 0.000324,
// 0.000586 / 0.000420, 0.000362 / 0.000320; material-spheres 0.000257 / 0.000278, 0.000264 /
// 0.000276, 0.000253 / 0.000257.
constexpr double kPathTracingPixelMargin = 1.1;
// The operation costs: the model, or what the probes measured (seconds summed over threads).
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
  t.light_vertex = per(w.light_seconds, w.light_vertices, t.light_vertex);
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

// Per pixel and iteration, from the probes' work (light paths at one per pixel).
struct PixelWork {
  // connections: light vertices connected per pixel with one connection per camera vertex
  // (from the probes', which make two: depth limits and early rejections make it far fewer than
  // vertices x vertices).
  double camera_vertices, connections, light_vertices_per_path, merge_queries, photons;
  double stop_camera_vertices, stop_merge_queries, stop_photons;
};

// A pixel's share of the light paths' cost.
double light_cost(const AdaptivePlan::Candidate& c, const PixelWork& w, const CostModel& t) {
  return c.light_path_factor * w.light_vertices_per_path * t.light_vertex;
}

// A pixel that path traces: pt's camera vertices, and its share of the light paths (which the
// other pixels use).
double path_tracing_cost(const AdaptivePlan::Candidate& c, const PixelWork& w, const CostModel& t) {
  return w.camera_vertices * t.path_tracing_vertex + light_cost(c, w, t);
}

// A pixel that runs the bidirectional core (without merging).
double base_cost(const AdaptivePlan::Candidate& c, const PixelWork& w, const CostModel& t) {
  if (c.light_path_factor == 0) return path_tracing_cost(c, w, t);
  const double connections =
      c.connections > 0 ? t.own_connection + (c.connections - 1) * t.connection : 0.0;
  return w.camera_vertices * t.camera_vertex + light_cost(c, w, t) + w.connections * connections;
}

// Photon density grows with the light paths: photons per query scale with the factor, and so
// does a query's price above one light path per pixel (CostModel::merge_query).
double merge_cost(const AdaptivePlan::Candidate& c, const PixelWork& w, const CostModel& t) {
  return w.merge_queries * query_price(c, t) + w.photons * c.light_path_factor * t.photon;
}

// A pixel that maps photons alone: its camera vertices up to the first non-delta scattering (no
// next event estimation there: priced as path tracing's, an upper bound), one query there, and
// its share of the light paths.
double stop_cost(const AdaptivePlan::Candidate& c, const PixelWork& w, const CostModel& t) {
  return w.stop_camera_vertices * t.path_tracing_vertex + w.stop_merge_queries * query_price(c, t) +
         w.stop_photons * c.light_path_factor * t.photon + light_cost(c, w, t);
}

void add_roulette_diff(uint8_t* diff, const AdaptivePlan::CandidateSums& sums) {
  for (size_t j = 0; j < AdaptivePlan::kCandidates; ++j)
    if (std::isfinite(sums.u[j])) put_float24(diff + 3 * j, get_float24(diff + 3 * j) + sums.u[j]);
}

MisCounts counts_of(const AdaptivePlan::Candidate& c, size_t pixels, float radius) {
  MisCounts n;
  n.emitter = 1;
  n.light_trace = c.light_path_factor * float(pixels);
  n.connect = c.light_path_factor > 0 ? float(c.connections) : 0.f;
  n.merge = c.merge ? n.light_trace * kPi * radius * radius : 0.f;
  return n;
}
}  // namespace

double fraction_of(const std::vector<PixelMode>& modes, PixelMode mode) {
  return modes.empty()
             ? 0.0
             : double(std::count(modes.begin(), modes.end(), mode)) / double(modes.size());
}

const std::vector<AdaptivePlan::Candidate>& AdaptivePlan::candidates() {
  static const std::vector<Candidate> list = [] {
    std::vector<Candidate> l{{0.f, 0, false}};  // path tracing
    for (float f : kLightPathFactors)
      for (int c : kConnections)
        for (bool m : {false, true}) l.push_back({f, c, m});
    for (float f : kLightPathFactors) l.push_back({f, 0, true});  // photon mapping
    return l;
  }();
  return list;
}

AdaptivePlan::AdaptivePlan(int width, int height, bool measured_costs, bool probe_every_iteration,
                           int probe_stride, int force_mode)
    : pixels_(size_t(width) * size_t(height)),
      width_(width),
      height_(height),
      measured_(measured_costs),
      probe_all_(probe_every_iteration),
      force_mode_(force_mode),
      modes_(pixels_, PixelMode::Merge) {
  if (probe_stride <= 0) probe_stride = int(std::floor(std::sqrt(double(pixels_) / kProbePixels)));
  stride_ = uint32_t(std::clamp(probe_stride, 1, std::max(1, std::min(width, height))));
  offset_ = (stride_ - 1) / 2;
  // The grid pixel (gx, gy) is the image pixel (gx s + o, gy s + o).
  grid_w_ = width > 0 ? int((uint32_t(width) - 1 - offset_) / stride_ + 1) : 0;
  grid_h_ = height > 0 ? int((uint32_t(height) - 1 - offset_) / stride_ + 1) : 0;
  grid_pixels_ = size_t(grid_w_) * size_t(grid_h_);
  moments_.assign(grid_pixels_ * kCandidates * 3, 0);  // float24 zeros
  roulette_diff_.assign(grid_pixels_ * kCandidates * 3, 0);
  chosen_.light_paths = pixels_;  // full VCM until the first probe is priced
  roulette_.fill(1.0);
}

template <typename T>
std::vector<T> AdaptivePlan::on_grid(const std::vector<T>& image) const {
  if (stride_ == 1 || image.size() != pixels_) return image;
  std::vector<T> grid(grid_pixels_);
  for (int gy = 0; gy < grid_h_; ++gy)
    for (int gx = 0; gx < grid_w_; ++gx)
      grid[size_t(gy) * grid_w_ + gx] =
          image[size_t(gy * stride_ + offset_) * width_ + (gx * stride_ + offset_)];
  return grid;
}

bool AdaptivePlan::is_probe(uint32_t iteration) const {
  return probe_all_ || iteration < kFirstProbes || iteration == next_probe_;
}

void AdaptivePlan::schedule_next_probe() {
  const uint64_t probe = probes_ <= kFirstProbes ? uint64_t(probes_ - 1) : next_probe_;
  const double choice = chosen_cost_, probe_cost = probe_cost_;
  // The predicted cost of the iterations up to this probe (those since the last probe at the
  // choice they rendered, and this probe; before the first choice every iteration was a
  // probe), and of what the probes cost beyond the choice they stood in for: their samples are
  // the image's as much as the choice's are.
  if (probe_iterations_.empty()) {
    spent_cost_ = double(probe + 1) * probe_cost;
    probe_excess_ = double(probe + 1) * std::max(0.0, probe_cost - choice);
  } else {
    spent_cost_ += double(probe - probe_iterations_.back() - 1) * last_choice_cost_ + probe_cost;
    probe_excess_ += std::max(0.0, probe_cost - last_choice_cost_);
  }
  probe_iterations_.push_back(probe);
  last_choice_cost_ = choice;
  // The doubling where there is no price, and with measured costs: those differ between MPI
  // ranks, which must agree on the probes (every rank renders them, and at a fixed --spp they
  // meet before each one).
  uint64_t gap = probe + 1;
  if (choice > 0 && probe_cost > 0 && !measured_) {
    // The next probe comes once the iterations after this one, the next probe included, have
    // cost what everything up to this one did: with one cost per iteration, iteration 2i + 1
    // after a probe at i (3, 7, 15, ...), and where the choice is much cheaper than a probe
    // (path tracing beside a probe's full VCM with two connections: 5x its cost on coffee) as
    // much later.
    gap = uint64_t(std::ceil(std::max(1.0, (spent_cost_ - probe_cost) / choice)));
    // No probe whose excess would take the probes beyond kMaxProbeShare of the render's
    // predicted cost (the rest of the budget at this choice): at 3, 7, 15, ... they took 22-35%
    // of 20 s at the scenes' own resolutions where the choice was cheap.
    const double rest = remaining_cost(probe, choice);
    if (std::isfinite(rest) &&
        probe_excess_ + std::max(0.0, probe_cost - choice) > kMaxProbeShare * (spent_cost_ + rest))
      gap = std::numeric_limits<uint32_t>::max();
  }
  next_probe_ = probe + 1 + gap;
  if (!history_.empty() && history_.back()["after_probe"] == probes_)
    history_.back()["next_probe"] = next_probe_ <= std::numeric_limits<uint32_t>::max()
                                        ? nlohmann::json(next_probe_)
                                        : nlohmann::json(nullptr);
}

void AdaptivePlan::set_budget(double iterations, double seconds, double elapsed) {
  budget_iterations_ = iterations;
  budget_seconds_ = seconds;
  elapsed_seconds_ = elapsed;
}

double AdaptivePlan::remaining_cost(uint64_t probe, double choice) const {
  // Infinite where no budget is known (the probes' share is then not bounded).
  double rest = std::numeric_limits<double>::infinity();
  if (budget_iterations_ > 0)  // --spp: the iterations after this probe, at the choice
    rest = std::max(0.0, budget_iterations_ - double(probe + 1)) * choice;
  if (budget_seconds_ > 0 && elapsed_seconds_ > 0)  // --time: the seconds left, at this pace
    rest = std::min(
        rest, std::max(0.0, budget_seconds_ - elapsed_seconds_) * spent_cost_ / elapsed_seconds_);
  return rest;
}

IterationPlan AdaptivePlan::plan(uint32_t iteration) const {
  if (is_probe(iteration) && stride_ == 1) {
    IterationPlan p;
    p.light_paths = pixels_;
    p.connections = kProbeConnections;
    p.probe_connections = kProbeConnections;
    p.merge_everywhere = true;
    p.probe = true;
    return p;
  }
  if (is_probe(iteration)) {
    // The other pixels render the last choice, with its light paths as far as the probe's
    // range allows: the probed pixels price every candidate from them (the proxy holds for any
    // probe counts) and need some, at least kSparseProbeLightPaths per pixel where path tracing
    // was chosen; and more than one per pixel made the probe dearer for no better choice
    // (door-ajar, which chooses two).
    IterationPlan p = chosen_;
    p.modes = &modes_;
    p.light_paths = std::clamp(chosen_.light_paths,
                               uint64_t(std::llround(kSparseProbeLightPaths * double(pixels_))),
                               uint64_t(pixels_));
    p.probe = true;
    p.probe_stride = stride_;
    p.probe_offset = offset_;
    p.width = uint32_t(width_);
    p.probe_connections = kProbeConnections;
    return p;
  }
  IterationPlan p = chosen_;
  p.modes = &modes_;
  return p;
}

void AdaptivePlan::begin_probe(float radius) {
  light_sums_.assign(grid_pixels_ * kLightSums * kCandidates, to_bfloat16(0.f));
  const std::vector<Candidate>& list = candidates();
  for (size_t j = 0; j < kCandidates; ++j) {
    const MisCounts n = counts_of(list[j], pixels_, radius);
    // The emitter class always counts 1 (counts_of): it is added unscaled in add().
    table_.light_trace[j] = n.light_trace;
    table_.connect[j] = n.connect;
    table_.merge[j] = n.merge;
    table_.emitter[j] = n.emitter;
  }
}

void AdaptivePlan::add(CandidateSums& sums, float value, const TechniqueTerms* terms,
                       const MisCounts& counts, Share share) const {
  if (!(value != 0.f) || !std::isfinite(value)) return;
  if (!terms) {
    for (size_t j = 0; j < kCandidates; ++j) sums.r[j] += value;
    return;
  }
  // The probe's counts are all positive, so a finite Q means finite terms: plain arithmetic.
  const float q = terms->denominator(counts), own = counts.of(terms->own);
  if (!(q > 0) || !std::isfinite(q) || !(own > 0)) return;
  const std::array<float, kCandidates>& own_count = table_.of(terms->own);
  const float f2 = value * value, inv_own = 1.f / own;
  const float emitter = terms->emitter, light_trace = terms->light_trace, connect = terms->connect,
              merge = terms->merge;
  // Photon mapping: the path's one technique there (TechniqueTerms::stop_own), no connections.
  for (size_t j = kCoreCandidates; j < kCandidates; ++j) {
    const float q_candidate = terms->stop_denominator(1.f, table_.merge[j]);
    const bool made = q_candidate > 0 && std::isfinite(q_candidate);
    const float ratio = made ? q / q_candidate : 0.f;
    const float own_g = value * ratio, scale = terms->stop_own(1.f, table_.merge[j]) * inv_own;
    const float g = own_g * scale;
    sums.u[j] += own_g * own_g * scale - f2 * ratio;
    sums.r[j] += g;  // 0 for connections, whatever their share
    sums.d[j] =
        sums.d[j] + f2 * ratio - g * g + (made ? 0.f : std::numeric_limits<float>::infinity());
  }
  std::array<float, kCandidates>& sum = share == Share::None           ? sums.r
                                        : share == Share::OwnLightPath ? sums.s0
                                                                       : sums.s1;
  // Written without branches, so that the loop vectorises (with -fno-trapping-math for this
  // file: src/CMakeLists.txt). A candidate none of whose techniques makes this path (Q' = 0)
  // would miss the energy: ratio 0, and D becomes infinite.
  for (size_t j = 0; j < kCoreCandidates; ++j) {
    const float q_candidate = own_count[j] + emitter + table_.light_trace[j] * light_trace +
                              table_.connect[j] * connect + table_.merge[j] * merge;
    const bool made = q_candidate > 0;
    const float ratio = q / (made ? q_candidate : q) * (made ? 1.f : 0.f);
    // The contribution under the candidate: a connection counts once per connection the
    // candidate makes (none if it makes none); other techniques scale with their sample count.
    const float scale = share == Share::None ? own_count[j] * inv_own : std::min(own_count[j], 1.f);
    const float g = value * ratio * scale;
    // How often g^2 enters the moment (pixel_end): a random light path's connection c' - 1
    // times.
    const float squares = share == Share::RandomLightPath ? own_count[j] - 1 : 1.f;
    // The candidate's own techniques' estimate of this sample's part of its diagonal: n'_t
    // samples where the probe took n_t (roulette_diff_).
    const float own_g = value * ratio;
    sums.u[j] += own_g * own_g * (own_count[j] * inv_own) - f2 * ratio;
    sum[j] += g;
    sums.d[j] = (sums.d[j] + f2 * ratio - squares * g * g) +
                (made ? 0.f : std::numeric_limits<float>::infinity());
  }
}

void AdaptivePlan::add_light_trace(size_t pixel, float value, const TechniqueTerms* terms,
                                   const MisCounts& counts) {
  CandidateSums sums = pixel_start(pixel);
  add(sums, value, terms, counts);
  uint16_t* stored = &light_sums_[grid_index(pixel) * kLightSums * kCandidates];
  for (size_t j = 0; j < kCandidates; ++j) {
    stored[j] = to_bfloat16(sums.r[j]);
    stored[kCandidates + j] = to_bfloat16(sums.d[j]);
    stored[2 * kCandidates + j] = to_bfloat16(sums.u[j]);
  }
}

AdaptivePlan::CandidateSums AdaptivePlan::pixel_start(size_t pixel) const {
  CandidateSums sums;
  const uint16_t* stored = &light_sums_[grid_index(pixel) * kLightSums * kCandidates];
  for (size_t j = 0; j < kCandidates; ++j) {
    sums.r[j] = from_bfloat16(stored[j]);
    sums.d[j] = from_bfloat16(stored[kCandidates + j]);
    sums.u[j] = from_bfloat16(stored[2 * kCandidates + j]);
  }
  return sums;
}

void AdaptivePlan::pixel_end(size_t pixel, const CandidateSums& sums) {
  const size_t g = grid_index(pixel);
  uint8_t* m = &moments_[g * kCandidates * 3];
  for (size_t j = 0; j < kCandidates; ++j) {
    const float c = table_.connect[j], r = sums.r[j], s0 = sums.s0[j], s1 = sums.s1[j];
    const float moment = r * r + 2 * r * (s0 + (c - 1) * s1) + s0 * s0 + (c - 1) * s1 * s1 +
                         c * (c - 1) * s0 * s1 + sums.d[j];
    put_float24(m + 3 * j, get_float24(m + 3 * j) + moment);
  }
  add_roulette_diff(&roulette_diff_[g * kCandidates * 3], sums);
}

void add_counts(ProbeWork& total, const ProbeWork& w) {
  total.light_paths += w.light_paths;
  total.light_vertices += w.light_vertices;
  total.light_rays += w.light_rays;
  total.camera_vertices += w.camera_vertices;
  total.nondelta_camera_vertices += w.nondelta_camera_vertices;
  total.connections += w.connections;
  total.merge_queries += w.merge_queries;
  total.photons += w.photons;
  total.stop_camera_vertices += w.stop_camera_vertices;
  total.stop_merge_queries += w.stop_merge_queries;
  total.stop_photons += w.stop_photons;
}

void AdaptivePlan::finish_probe(const ProbeWork& w, const std::vector<float>& means,
                                const std::vector<double>& measured, double iterations,
                                double thread_seconds) {
  ++probes_;
  // The light-tracing sums (6 bytes per pixel and candidate) are only needed while a probe
  // renders; released before the choice, so that its buffers do not add to them.
  std::vector<uint16_t>().swap(light_sums_);
  // The cost model's photons are those of one light path per pixel (merge_cost scales them
  // with a candidate's factor); a sparse probe traces the chosen light paths.
  ProbeWork normalized = w;
  if (w.light_paths > 0) {
    normalized.photons *= double(pixels_) / w.light_paths;
    normalized.stop_photons *= double(pixels_) / w.light_paths;
  }
  add_counts(work_, normalized);
  work_.light_seconds += w.light_seconds;
  work_.camera_seconds += w.camera_seconds;
  work_.connect_seconds += w.connect_seconds;
  work_.merge_seconds += w.merge_seconds;
  if (means.size() != pixels_) {
    if (probes_ >= kFirstProbes) schedule_next_probe();
    return;
  }
  const std::vector<float> grid_means = on_grid(means);
  if (measured.size() == pixels_ && chosen_j_ < kCandidates)
    check_last_choice(on_grid(measured), iterations, thread_seconds, grid_means);
  // A choice needs the film's means (from the iterations before the probe) and two probes.
  if (probes_ >= kFirstProbes || probe_all_) choose(grid_means);
  if (probes_ >= kFirstProbes) schedule_next_probe();
}

void AdaptivePlan::check_last_choice(const std::vector<double>& measured, double iterations,
                                     double thread_seconds, const std::vector<float>& means) {
  // The measured relative variance, pooled as the prediction was; both capped at the
  // prediction's 99.5th percentile, so that a firefly that one segment happened to render (or
  // that the prediction's winsorising took out) does not decide the comparison alone.
  std::vector<double> relative(grid_pixels_);
  for (size_t p = 0; p < grid_pixels_; ++p)
    relative[p] = measured[p] / (double(means[p]) * means[p] + kRelEps);
  relative = box_blur(relative, grid_w_, grid_h_, kBlurRadius);
  const double cap = finite_quantile(chosen_variance_, kWinsorize);
  std::vector<std::array<double, 2>> blocks((grid_pixels_ + kPixelBlock - 1) / kPixelBlock);
  for_pixel_blocks(grid_pixels_, [&](size_t b, size_t begin, size_t end) {
    std::array<double, 2> sum{};
    for (size_t p = begin; p < end; ++p) {
      if (!std::isfinite(chosen_variance_[p]) || !std::isfinite(relative[p])) continue;
      sum[0] += std::min(relative[p], cap);
      sum[1] += std::min(chosen_variance_[p], cap);
    }
    blocks[b] = sum;
  });
  double measured_total = 0, predicted_total = 0;
  for (const std::array<double, 2>& sum : blocks) {
    measured_total += sum[0];
    predicted_total += sum[1];
  }
  checks_.push_back({{"after_probe", probes_},
                     {"light_path_factor", candidates()[chosen_j_].light_path_factor},
                     {"connections", candidates()[chosen_j_].connections},
                     {"iterations", iterations},
                     {"measured_relative_variance", measured_total / double(grid_pixels_)},
                     {"predicted_relative_variance", predicted_total / double(grid_pixels_)},
                     // Not deterministic (a clock); with the fixed cost model the two differ by
                     // the machine's speed, so compare their ratio across choices.
                     {"measured_us_per_pixel",
                      iterations > 0 ? 1e6 * thread_seconds / (iterations * double(pixels_)) : 0.0},
                     {"predicted_us_per_pixel", chosen_cost_}});
}

double AdaptivePlan::relative_variance(size_t p, size_t j, const std::vector<float>& means) const {
  const double mean = means[p];
  const double moment = get_float24(&moments_[(p * kCandidates + j) * 3]) / double(probes_);
  // Signed: clamped only after pooling (relative_variances).
  return (moment - mean * mean) / (mean * mean + kRelEps) * roulette_[j];
}

void AdaptivePlan::update_roulette_factors(const std::vector<float>& means) {
  roulette_.fill(1.0);
  // Per candidate (in parallel; each in pixel order, so deterministic): the sum of its finite
  // relative variances and of the relative roulette differences, these winsorised at their
  // 99.5th percentile as the shared variance is (the own techniques' estimate is heavy-tailed:
  // on a 32 x 32 Cornell box path tracing's factor ranged 1.15-1.43 over the probes without it,
  // against 1.07 from 400 probes).
  tbb::parallel_for(size_t(0), kCandidates, [&](size_t j) {
    std::vector<double> diff(grid_pixels_);
    double variance = 0;
    for (size_t p = 0; p < grid_pixels_; ++p) {
      const double v = relative_variance(p, j, means);
      diff[p] = std::numeric_limits<double>::infinity();
      if (!std::isfinite(v)) continue;
      variance += v;
      diff[p] = get_float24(&roulette_diff_[(p * kCandidates + j) * 3]) /
                (double(probes_) * (double(means[p]) * means[p] + kRelEps));
    }
    const double cap = finite_quantile(diff, kWinsorize);
    double total = 0;
    for (double d : diff)
      if (std::isfinite(d)) total += std::min(d, cap);
    const double factor = variance > 0 ? 1.0 + total / variance : 1.0;
    roulette_[j] = std::isfinite(factor) ? std::max(factor, 1.0) : 1.0;
  });
}

std::vector<double> AdaptivePlan::shared_firefly_correction(const std::vector<float>& means) const {
  // The part of a pixel's variance every candidate has (the least of them) is winsorised at its
  // 99.5th percentile over the pixels: a firefly that a few probes saw in a handful of pixels,
  // and that every candidate shares, is mostly estimation noise; at full weight it drowns the
  // differences everywhere else and lets the cheapest candidate win. What a candidate has beyond
  // the least (its own fireflies: missing connections, fewer light paths) is kept in full.
  std::vector<double> shared(grid_pixels_);
  for_pixel_blocks(grid_pixels_, [&](size_t, size_t begin, size_t end) {
    for (size_t p = begin; p < end; ++p) {
      double least = std::numeric_limits<double>::infinity();
      for (size_t j = 0; j < kCandidates; ++j)
        least = std::min(least, relative_variance(p, j, means));
      shared[p] = least;
    }
  });
  std::vector<double> sorted = shared;
  const size_t q = std::min(grid_pixels_ - 1, size_t(double(grid_pixels_) * kWinsorize));
  std::nth_element(sorted.begin(), sorted.begin() + q, sorted.end());
  const double cap = sorted[q];
  for (double& x : shared) x = std::isfinite(x) && x > cap ? cap - x : 0.0;
  return shared;
}

std::vector<double> AdaptivePlan::relative_variances(size_t j, const std::vector<float>& means,
                                                     const std::vector<double>& correction) const {
  std::vector<double> v(grid_pixels_);
  for_pixel_blocks(grid_pixels_, [&](size_t, size_t begin, size_t end) {
    for (size_t p = begin; p < end; ++p) v[p] = relative_variance(p, j, means) + correction[p];
  });
  v = box_blur(v, grid_w_, grid_h_, kBlurRadius);
  for (double& x : v) x = std::max(x, 0.0);  // inf stays inf
  return v;
}

void AdaptivePlan::choose(const std::vector<float>& means) {
  const std::vector<Candidate>& list = candidates();
  const size_t k = kCoreCandidates;
  const double probes = double(probes_), pixels = double(grid_pixels_);
  const PixelWork pw{work_.camera_vertices / (probes * pixels),
                     work_.connections / (probes * pixels * kProbeConnections),
                     work_.light_paths > 0 ? work_.light_vertices / work_.light_paths : 0.0,
                     work_.merge_queries / (probes * pixels),
                     work_.photons / (probes * pixels),
                     work_.stop_camera_vertices / (probes * pixels),
                     work_.stop_merge_queries / (probes * pixels),
                     work_.stop_photons / (probes * pixels)};
  const CostModel t = costs_of(work_, measured_);
  update_roulette_factors(means);
  const std::vector<double> correction = shared_firefly_correction(means);
  const std::vector<double> pt = relative_variances(0, means, correction);
  // Photon mapping per light-path factor (kLightPathFactors' order).
  std::array<std::vector<double>, kStopCandidates> stop;
  for (size_t i = 0; i < kStopCandidates; ++i)
    stop[i] = relative_variances(kCoreCandidates + i, means, correction);
  auto stop_index = [&](float factor) {
    for (size_t i = 0; i < kStopCandidates; ++i)
      if (list[kCoreCandidates + i].light_path_factor == factor) return i;
    return kStopCandidates;
  };
  // Candidates compare by the pixels where their variance is infinite (energy they would miss:
  // paths none of their techniques there can make), then by score. Path tracing is the
  // default only among equals.
  struct Score {
    double missing = std::numeric_limits<double>::infinity();
    double value = std::numeric_limits<double>::infinity();
    bool operator<(const Score& o) const {
      return missing != o.missing ? missing < o.missing : value < o.value;
    }
  };
  Score best, path_tracing;
  size_t best_j = 0;
  double best_cost = 0, pt_cost = 0;
  std::vector<PixelMode> modes(grid_pixels_), best_modes(grid_pixels_, PixelMode::PathTrace);
  std::vector<double> variances(grid_pixels_), best_variances(grid_pixels_), pt_variances;
  nlohmann::json table = nlohmann::json::array();
  // Candidates come in (no merge, merge) pairs after path tracing at index 0.
  for (size_t j = 0; j < k; j += (j == 0 ? 1 : 2)) {
    const Candidate& c = list[j];
    const double cost = base_cost(c, pw, t);
    const double extra = j == 0 ? 0.0 : merge_cost(list[j + 1], pw, t);
    const double traced = path_tracing_cost(c, pw, t);
    const std::vector<double> no_merge = j == 0 ? pt : relative_variances(j, means, correction);
    const std::vector<double> merge = j == 0 ? pt : relative_variances(j + 1, means, correction);
    const size_t si = j == 0 ? kStopCandidates : stop_index(c.light_path_factor);
    const std::vector<double>* stops = si < kStopCandidates ? &stop[si] : nullptr;
    const double stopped = stops ? stop_cost(list[kCoreCandidates + si], pw, t) : 0.0;
    // Per pixel, the option of lowest variance x cost: path tracing alone (where it is as good
    // as the light paths' techniques, it is cheaper: a caustic that only light paths make need
    // not make every pixel pay for the bidirectional core), the core, or the core and merging.
    // Photon mapping alone where it beats the core (ppm's estimator: a caustic seen on a
    // diffuse surface needs no connections or light tracing there).
    // Per block of pixels: finite variance, cost, variance without and with merging and with
    // photon mapping everywhere, pixels of infinite variance.
    std::vector<std::array<double, 6>> blocks((grid_pixels_ + kPixelBlock - 1) / kPixelBlock);
    for_pixel_blocks(grid_pixels_, [&](size_t b, size_t begin, size_t end) {
      std::array<double, 6> sum{};
      for (size_t p = begin; p < end; ++p) {
        const double v0 = no_merge[p], v1 = merge[p], vt = pt[p];
        const double vs = stops ? (*stops)[p] : std::numeric_limits<double>::infinity();
        sum[2] += v0;
        sum[3] += v1;
        sum[5] += vs;
        // The core, with merging where that is better; path tracing where it beats both.
        double v = v0, pixel_cost = cost;
        modes[p] = PixelMode::Bidirectional;
        if (v1 * (cost + extra) < v0 * cost) {
          v = v1;
          pixel_cost = cost + extra;
          modes[p] = PixelMode::Merge;
        }
        if (vs * stopped < v * pixel_cost) {
          v = vs;
          pixel_cost = stopped;
          modes[p] = PixelMode::Stop;
        }
        if (j == 0 || (vt * traced <= v * pixel_cost && std::isfinite(vt) &&
                       vt <= kPathTracingPixelMargin * std::min(v0, v1))) {
          v = vt;
          pixel_cost = traced;
          modes[p] = PixelMode::PathTrace;
        }
        variances[p] = v;
        if (std::isfinite(v))
          sum[0] += v;
        else
          sum[4] += 1;
        sum[1] += pixel_cost;
      }
      blocks[b] = sum;
    });
    double variance = 0, total_cost = 0, variance0 = 0, variance1 = 0, missing = 0, variance_s = 0;
    for (const std::array<double, 6>& sum : blocks) {
      variance += sum[0];
      total_cost += sum[1];
      variance0 += sum[2];
      variance1 += sum[3];
      missing += sum[4];
      variance_s += sum[5];
    }
    const Score score{missing, variance * total_cost};
    table.push_back({{"light_path_factor", c.light_path_factor},
                     {"connections", c.connections},
                     {"merge_fraction", fraction_of(modes, PixelMode::Merge)},
                     {"path_trace_fraction", fraction_of(modes, PixelMode::PathTrace)},
                     {"relative_variance", variance / pixels},
                     {"relative_variance_no_merge", variance0 / pixels},
                     {"relative_variance_all_merge", variance1 / pixels},
                     {"stop_fraction", fraction_of(modes, PixelMode::Stop)},
                     {"relative_variance_all_stop", stops ? variance_s / pixels : -1.0},
                     {"cost_us_per_pixel_stop", stopped},
                     {"cost_us_per_pixel", total_cost / pixels},
                     {"pixels_missing_energy", missing},
                     {"roulette_factor", roulette_[j]},
                     {"roulette_factor_merge", j == 0 ? roulette_[j] : roulette_[j + 1]},
                     {"score", score.value}});
    if (j == 0) path_tracing = score;
    // A forced mode other than path tracing needs light paths (force_mode_).
    const bool excluded = j == 0 && force_mode_ >= 0 && force_mode_ != int(PixelMode::PathTrace);
    if (score < best && !excluded) {
      best = score;
      best_j = j;
      best_modes = modes;
      best_variances = variances;
      best_cost = total_cost / pixels;
    }
    if (j == 0) {
      pt_variances = variances;
      pt_cost = total_cost / pixels;
    }
  }
  if (best_j != 0 && force_mode_ < 0 && path_tracing.missing == best.missing &&
      path_tracing.value <= kPathTracingMargin * best.value) {
    best_j = 0;
    std::fill(best_modes.begin(), best_modes.end(), PixelMode::PathTrace);
    best_variances = pt_variances;
    best_cost = pt_cost;
  }
  if (force_mode_ >= 0 && best_j != 0)
    std::fill(best_modes.begin(), best_modes.end(), PixelMode(force_mode_));
  chosen_j_ = best_j;
  chosen_variance_ = std::move(best_variances);
  chosen_cost_ = best_cost;
  const Candidate& c = list[best_j];
  chosen_ = {};
  chosen_.light_paths = uint64_t(std::llround(double(c.light_path_factor) * double(pixels_)));
  chosen_.connections = c.connections;
  chosen_.merge_everywhere = false;
  // Each image pixel takes the mode of its block's probed pixel (the last row and column of
  // grid pixels also cover what is left of the image beyond them).
  for (int y = 0; y < height_; ++y) {
    const size_t gy = std::min(size_t(y) / stride_, size_t(grid_h_ - 1));
    for (int x = 0; x < width_; ++x) {
      const size_t gx = std::min(size_t(x) / stride_, size_t(grid_w_ - 1));
      modes_[size_t(y) * width_ + x] = best_modes[gy * grid_w_ + gx];
    }
  }
  // A probe's predicted cost: its recorded pixels at the probe's configuration (one light path
  // per pixel, two connections, merging), times what recording every contribution adds; the
  // others at the choice, with the probe's light paths (at least kSparseProbeLightPaths).
  const Candidate probe_config{1.f, kProbeConnections, true};
  const double recorded = double(grid_pixels_) / double(pixels_);
  const double choice_paths = double(chosen_.light_paths) / double(pixels_);
  const double probe_paths =
      stride_ > 1 ? std::clamp(choice_paths, kSparseProbeLightPaths, 1.0) : choice_paths;
  probe_cost_ = recorded * (base_cost(probe_config, pw, t) + merge_cost(probe_config, pw, t)) *
                    kProbeRecordingFactor +
                (1 - recorded) * (best_cost + (probe_paths - choice_paths) *
                                                  pw.light_vertices_per_path * t.light_vertex);
  history_.push_back({{"after_probe", probes_},
                      {"predicted_probe_us_per_pixel", probe_cost_},
                      {"light_path_factor", c.light_path_factor},
                      {"connections", c.connections},
                      {"merge_fraction", fraction_of(modes_, PixelMode::Merge)},
                      {"path_trace_fraction", fraction_of(modes_, PixelMode::PathTrace)},
                      {"stop_fraction", fraction_of(modes_, PixelMode::Stop)},
                      {"costs_us",
                       {{"camera_vertex", t.camera_vertex},
                        {"path_tracing_vertex", t.path_tracing_vertex},
                        {"light_vertex", t.light_vertex},
                        {"connection", t.connection},
                        {"own_connection", t.own_connection},
                        {"merge_query", t.merge_query},
                        {"photon", t.photon}}},
                      {"candidates", table}});
}

}  // namespace caustica::bidir
