#include "integrators/bidir/adaptive_plan.h"

#include <algorithm>
#include <chrono>
#include <cmath>
#include <limits>
#include <nlohmann/json.hpp>

#include "core/compact_float.h"
#include "core/math.h"
#include "integrators/bidir/grid_statistics.h"

namespace caustica::bidir {

namespace {
constexpr float kLightPathFactors[] = {0.25f, 0.5f, 1.f, 2.f};
constexpr int kConnections[] = {0, 1, 2, 4, 8};

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

using Share = AdaptivePlan::Share;

// One recorded contribution's values that every core candidate's term in add() shares.
struct CoreTerms {
  float q, value, f2, inv_own, emitter, light_trace, connect, merge;
};

// The core candidates' part of add() for one kind of share, candidates [begin, end), without a
// branch, so that the loop vectorises (GCC 12 at -O3: four candidates per SSE instruction; the
// loop as add() once wrote it, with selections around the division, stayed scalar). The
// pointers are parameters because GCC honours restrict only there. unmade: what D gains where
// the candidate does not make the path (Q' = 0), a constant per call: GCC turns a table of it
// into a value carried from one iteration to the next, which does not vectorise.
template <Share kShare>
void add_core(size_t begin, size_t end, float unmade, float* __restrict sum, float* __restrict u,
              float* __restrict d, const float* __restrict own_count, const float* __restrict lt,
              const float* __restrict cn, const float* __restrict mg, const CoreTerms t) {
  for (size_t j = begin; j < end; ++j) {
    const float q_candidate =
        own_count[j] + t.emitter + lt[j] * t.light_trace + cn[j] * t.connect + mg[j] * t.merge;
    // made: 1 where the candidate makes the path, else 0. Then ratio = q / Q', or 0: the
    // divisor is Q' + 0 (exact) or 1, so that no division depends on a condition.
    const float made = q_candidate > 0 ? 1.f : 0.f;
    const float ratio = t.q / (q_candidate + (1.f - made)) * made;
    // The contribution under the candidate: a connection counts once per connection the
    // candidate makes (none if it makes none); other techniques scale with their sample count.
    const float scale =
        kShare == Share::None ? own_count[j] * t.inv_own : std::min(own_count[j], 1.f);
    const float g = t.value * ratio * scale;
    // How often g^2 enters the moment (pixel_end): a random light path's connection c' - 1
    // times.
    const float squares = kShare == Share::RandomLightPath ? own_count[j] - 1 : 1.f;
    // The candidate's own techniques' estimate of this sample's part of its diagonal: n'_t
    // samples where the probe took n_t (roulette_diff_).
    const float own_g = t.value * ratio;
    u[j] += own_g * own_g * (own_count[j] * t.inv_own) - t.f2 * ratio;
    sum[j] += g;
    d[j] = (d[j] + t.f2 * ratio - squares * g * g) + (made > 0 ? 0.f : unmade);
  }
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
  moments_odd_.assign(grid_pixels_ * kCandidates * 3, 0);
  roulette_diff_.assign(grid_pixels_ * kCandidates * 3, 0);
  pixel_vertices_.assign(grid_pixels_, 0.f);
  pt_missing_.assign(grid_pixels_, 0.f);
  probe_missing_.assign(grid_pixels_, 0.f);
  pooled_missing_squares_.assign(grid_pixels_, 0.0);
  probe_estimate_.assign(grid_pixels_, 0.f);
  mean_square_sums_.assign(grid_pixels_, 0.0);
  estimate_sums_.assign(grid_pixels_, 0.0);
  estimate_square_sums_.assign(grid_pixels_, 0.0);
  chosen_.light_paths = pixels_;  // full VCM until the first probe is priced
  roulette_.fill(1.0);
}

std::vector<size_t> AdaptivePlan::grid_image_pixels() const {
  std::vector<size_t> pixels(grid_pixels_);
  for (int gy = 0; gy < grid_h_; ++gy)
    for (int gx = 0; gx < grid_w_; ++gx)
      pixels[size_t(gy) * grid_w_ + gx] =
          size_t(gy * stride_ + offset_) * width_ + (gx * stride_ + offset_);
  return pixels;
}

template <typename T>
std::vector<T> AdaptivePlan::on_grid(const std::vector<T>& image) const {
  if (stride_ == 1 || image.size() != pixels_) return image;
  const std::vector<size_t> pixels = grid_image_pixels();
  std::vector<T> grid(grid_pixels_);
  for (size_t g = 0; g < grid_pixels_; ++g) grid[g] = image[pixels[g]];
  return grid;
}
template std::vector<float> AdaptivePlan::on_grid(const std::vector<float>&) const;

bool AdaptivePlan::is_probe(uint32_t iteration) const {
  return probe_all_ || iteration < kFirstProbes || iteration == next_probe_;
}

void AdaptivePlan::schedule_next_probe() {
  const uint64_t probe = probes_ <= kFirstProbes ? uint64_t(probes_ - 1) : next_probe_;
  const double choice = chosen_cost_, probe_cost = probe_cost_;
  const double segment_choice = last_choice_cost_;  // the choice the last segment rendered
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
    // A choice that repeated the last one k times in a row (settled_choices_) waits k + 1 times
    // as long: a probe is worth its cost while the choice may still change, and the probes of a
    // scene that path traces every pixel (full VCM beside path tracing) took 14% of 20 s on
    // material-testball, which lost 1.12x to pt for it (docs/adaptive-vcm.md).
    gap = uint64_t(std::ceil(
        std::max(1.0, double(1 + settled_choices_) * (spent_cost_ - probe_cost) / choice)));
    // No probe whose excess would take the probes beyond kMaxProbeShare of the render's
    // predicted cost (the rest of the budget at this choice): at 3, 7, 15, ... they took 22-35%
    // of 20 s at the scenes' own resolutions where the choice was cheap.
    const double rest = remaining_cost(probe, choice);
    if ((std::isfinite(rest) && probe_excess_ + std::max(0.0, probe_cost - choice) >
                                    probe_share() * (spent_cost_ + rest)) ||
        probe_seconds_exceed_share(choice, segment_choice, probe_cost))
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

void AdaptivePlan::set_times(double probe_seconds, double segment_seconds,
                             double segment_iterations) {
  last_probe_seconds_ = probe_seconds - probe_seconds_;
  probe_seconds_ = probe_seconds;
  segment_iteration_seconds_ = segment_iterations > 0 ? segment_seconds / segment_iterations : 0;
}

bool AdaptivePlan::probe_seconds_exceed_share(double choice, double segment_choice,
                                              double probe_cost) const {
  if (!(budget_seconds_ > 0) || !(last_probe_seconds_ > 0) || !(choice > 0) || !(probe_cost > 0))
    return false;
  const double iteration = segment_iteration_seconds_ > 0 && segment_choice > 0
                               ? segment_iteration_seconds_ * choice / segment_choice
                               : last_probe_seconds_ * choice / probe_cost;
  const double excess = std::max(0.0, probe_seconds_ - double(probes_) * iteration);
  const double next = std::max(0.0, last_probe_seconds_ - iteration);
  return excess + next > probe_share() * budget_seconds_;
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
    p.splats_nowhere = false;  // the recorded pixels take them
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
  std::fill(probe_missing_.begin(), probe_missing_.end(), 0.f);
  light_sums_.assign(grid_pixels_ * kLightSums * kCandidates, to_bfloat16(0.f));
  light_missing_pt_.assign(grid_pixels_, 0.f);
  light_estimate_.assign(grid_pixels_, 0.f);
  std::fill(probe_estimate_.begin(), probe_estimate_.end(), 0.f);
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
  sums.estimate += value;
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
  const CoreTerms t{q, value, f2, inv_own, emitter, light_trace, connect, merge};
  float *u = sums.u.data(), *d = sums.d.data();
  const float *own_n = own_count.data(), *lt = table_.light_trace.data(),
              *cn = table_.connect.data(), *mg = table_.merge.data();
  float* sum = share == Share::None           ? sums.r.data()
               : share == Share::OwnLightPath ? sums.s0.data()
                                              : sums.s1.data();
  // Path tracing (candidate 0) keeps its variance where it cannot make the path (the energy it
  // misses is kept apart below); every other candidate that misses it gets an infinite D.
  constexpr float kInf = std::numeric_limits<float>::infinity();
  auto core = [&](auto kind) {
    constexpr Share kShare = decltype(kind)::value;
    add_core<kShare>(0, 1, 0.f, sum, u, d, own_n, lt, cn, mg, t);
    add_core<kShare>(1, kCoreCandidates, kInf, sum, u, d, own_n, lt, cn, mg, t);
  };
  switch (share) {
    case Share::None:
      core(std::integral_constant<Share, Share::None>());
      break;
    case Share::OwnLightPath:
      core(std::integral_constant<Share, Share::OwnLightPath>());
      break;
    case Share::RandomLightPath:
      core(std::integral_constant<Share, Share::RandomLightPath>());
      break;
  }
  // Candidate 0 (path tracing) has no light paths: only its own emitter class makes paths.
  if (!(own_count[0] + emitter + table_.light_trace[0] * light_trace + table_.connect[0] * connect +
            table_.merge[0] * merge >
        0))
    sums.missing_pt += value;
}

void AdaptivePlan::add_light_trace(size_t pixel, float value, const TechniqueTerms* terms,
                                   const MisCounts& counts) {
  CandidateSums sums = pixel_start(pixel);
  add(sums, value, terms, counts);
  light_missing_pt_[grid_index(pixel)] = sums.missing_pt;
  light_estimate_[grid_index(pixel)] = sums.estimate;
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
  sums.missing_pt = light_missing_pt_.empty() ? 0.f : light_missing_pt_[grid_index(pixel)];
  sums.estimate = light_estimate_.empty() ? 0.f : light_estimate_[grid_index(pixel)];
  return sums;
}

void AdaptivePlan::pixel_end(size_t pixel, const CandidateSums& sums, double camera_vertices) {
  const size_t g = grid_index(pixel);
  pixel_vertices_[g] += float(camera_vertices);  // integers: exact far beyond any probe count
  pt_missing_[g] += sums.missing_pt;
  probe_missing_[g] += sums.missing_pt;
  probe_estimate_[g] += sums.estimate;
  uint8_t* m = &moments_[g * kCandidates * 3];
  uint8_t* odd = probes_ % 2 == 1 ? &moments_odd_[g * kCandidates * 3] : nullptr;
  for (size_t j = 0; j < kCandidates; ++j) {
    const float c = table_.connect[j], r = sums.r[j], s0 = sums.s0[j], s1 = sums.s1[j];
    const float moment = r * r + 2 * r * (s0 + (c - 1) * s1) + s0 * s0 + (c - 1) * s1 * s1 +
                         c * (c - 1) * s0 * s1 + sums.d[j];
    put_float24(m + 3 * j, get_float24(m + 3 * j) + moment);
    if (odd) put_float24(odd + 3 * j, get_float24(odd + 3 * j) + moment);
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
  for (size_t p = 0; p < grid_pixels_; ++p) {
    estimate_sums_[p] += probe_estimate_[p];
    estimate_square_sums_[p] += double(probe_estimate_[p]) * probe_estimate_[p];
  }
  {
    std::vector<double> pooled(probe_missing_.begin(), probe_missing_.end());
    pooled = box_blur(pooled, grid_w_, grid_h_, kPoolRadius);
    for (size_t p = 0; p < grid_pixels_; ++p) pooled_missing_squares_[p] += pooled[p] * pooled[p];
  }
  // The light-tracing sums (6 bytes per pixel and candidate) are only needed while a probe
  // renders; released before the choice, so that its buffers do not add to them.
  std::vector<uint16_t>().swap(light_sums_);
  std::vector<float>().swap(light_missing_pt_);
  std::vector<float>().swap(light_estimate_);
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
  for (size_t p = 0; p < grid_pixels_; ++p)
    mean_square_sums_[p] += double(grid_means[p]) * double(probe_estimate_[p]);
  ++mean_square_probes_;
  if (measured.size() == grid_pixels_ && chosen_j_ < kCandidates)
    check_last_choice(measured, iterations, thread_seconds, grid_means);
  // A choice needs the film's means (from the iterations before the probe) and two probes.
  if (probes_ >= kFirstProbes || probe_all_) {
    const auto start = std::chrono::steady_clock::now();
    choose(grid_means);
    // Not deterministic (a clock): what choosing took, beside the probe's rendering.
    history_.back()["choice_seconds"] =
        std::chrono::duration<double>(std::chrono::steady_clock::now() - start).count();
  }
  if (probes_ >= kFirstProbes) schedule_next_probe();
}

}  // namespace caustica::bidir
