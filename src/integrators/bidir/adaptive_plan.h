// The scene-adaptive configuration of the bidirectional core (adaptive-vcm), after Grittmann,
// Yazici, Georgiev and Slusallek 2022, "Efficiency-Aware Multiple Importance Sampling for
// Bidirectional Rendering Algorithms".
//
// A configuration is the number of light paths per iteration (0: path tracing with NEE and MIS,
// up to 2x the pixel count), the number of light paths each camera vertex connects to
// (0, 1, 2, 4, 8) and, per pixel, a mode (PixelMode: path trace alone, the core, the core and
// merging). Probe iterations render full
// VCM (one light path per pixel, two connections per camera vertex: the pixel's own light path
// and one drawn at random, merging everywhere) and record every contribution F of every pixel
// with its MIS terms. Under the balance heuristic the second
// moment of a pixel under counts n' is the integral of f^2 / sum_k n'_k p_k; the probe's samples
// estimate it as sum F^2 * Q / Q', where Q and Q' are the MIS denominators of the sample's path
// under the probe's and the candidate's counts (mis.h: TechniqueTerms::denominator). That is
// the paper's proxy-weight correction factor: one probe prices every candidate, including ones
// it never rendered. The cross terms of contributions that share a camera prefix are kept
// (AdaptivePlan::add); the probe's two connections per vertex tell those that share the
// pixel's light path from those that do not.
//
// Cost: per candidate, the predicted time of an iteration from the probes' counts (camera
// vertices, light vertices, connections, merge queries and photons) times per-operation costs,
// either measured in the probes on this machine (non-deterministic, used with --time) or the
// fixed model below (deterministic). A pixel's camera-pass part of that cost scales with its own
// camera vertices in the probes (pixel_vertices_). The choice minimises sum_p relVar_p x cost: for
// each global (light paths, connections) the pixels take the modes of lowest total variance x total
// cost (pixel_modes.h: per pixel the lowest v / V + c / C at the image's means V and C), path
// tracing only where its variance is within a margin of the core's; that mix competes with every
// pixel in one mode (the core, the core and merging, photon mapping). The minimum per pixel over
// noisy estimates is biased low, so the mix is priced cross-fitted: the modes that the even
// probes choose are priced on the odd probes' variances and vice versa, and every option of
// every pair is scored from the two halves alike. Then the global pair wins that misses energy
// (infinite variance: paths none of its techniques make) in the fewest pixels, and among those
// has the lowest total.
//
// Probes are iterations 0 and 1, then each once the iterations since the last one have cost
// (predicted by the fixed model) what everything before it did, so their cost fades as the
// render grows (with one cost per iteration: 3, 7, 15, 31, ...; k + 1 times as long after a
// choice that repeated the one before k times in a row), and none that would take the
// probes beyond kMaxProbeShare of the budget's predicted time in excess of the choice they stand
// in for (schedule_next_probe; with --time also of the seconds they took, set_times). On an image
// of more than kProbePixels pixels a probe records one pixel per block of the image and the
// estimates below are of that grid of pixels; the others render the last choice
// (IterationPlan::records), with its light paths (kSparseProbeLightPaths to one per pixel) once
// there is one. The first choice is made after the second probe; the variance all candidates share
// is winsorised at its 99.5th percentile over the pixels (a shared firefly must not decide) and
// pooled over 7 x 7 neighbours before the per-pixel decision (a handful of samples per pixel would
// otherwise decide by luck; an infinite variance makes its whole window infinite). Iterations and
// pixels that path trace (and are not probes) are rendered by pt's own estimator (path_tracer.h,
// power heuristic unless --mis says otherwise), cheaper than the core's camera subpaths, and no
// light-tracing splat lands in such a pixel; the cost model prices their camera vertices
// separately. Every iteration, probe or not, is an unbiased (consistent, when merging) estimate of
// the same image, and the film averages them. Deterministic at fixed spp and seed for any thread
// count unless measured costs are asked for, and for any number of MPI ranks: every rank renders
// every probe, normalised by the film of all ranks (Integrator::shared_iteration).
#pragma once

#include <algorithm>
#include <array>
#include <cstdint>
#include <nlohmann/json.hpp>
#include <vector>

#include "integrators/bidir/mis.h"

namespace caustica::bidir {

// What a pixel does in an iteration that follows a choice (not a probe): the bidirectional
// core's camera subpaths without or with merging, path tracing alone (pt's estimator; no
// light-tracing splat lands in the pixel, so its MIS weights are pt's), or photon mapping alone
// (ppm's estimator: the camera subpath ends at its first vertex scattered through a non-delta
// lobe and merges there, emitters count only through delta chains; no light-tracing splat
// lands in the pixel, every weight is 1).
enum class PixelMode : uint8_t { Bidirectional = 0, Merge = 1, PathTrace = 2, Stop = 3 };

// What one iteration renders.
struct IterationPlan {
  uint64_t light_paths = 0;  // 0: camera paths only (path tracing)
  int connections = 1;       // light paths each camera vertex connects to
  bool merge_everywhere = true;
  const std::vector<PixelMode>* modes = nullptr;  // per pixel, when !merge_everywhere
  bool probe = false;                             // record contributions for the planner
  // No pixel takes light-tracing splats: every one path traces or maps photons alone (a
  // choice's modes, never a probe), so that the light subpaths make no lens connection.
  bool splats_nowhere = false;
  // A probe records every pixel (probe_stride 1) or, on a large image, the pixel at
  // (probe_offset, probe_offset) of each probe_stride x probe_stride block of the image
  // (width pixels wide): those render the probe's configuration (merging, probe_connections),
  // every other pixel renders the last choice (modes, connections), all with light_paths.
  uint32_t probe_stride = 1, probe_offset = 0, width = 0;
  int probe_connections = 1;
  bool records(size_t pixel) const {
    if (!probe) return false;
    if (probe_stride == 1) return true;
    return (pixel % width) % probe_stride == probe_offset &&
           (pixel / width) % probe_stride == probe_offset;
  }
  int connections_at(size_t pixel) const {
    return records(pixel) ? probe_connections : connections;
  }
  bool merges(size_t pixel) const {
    return light_paths > 0 &&
           (merge_everywhere || records(pixel) ||
            (modes && ((*modes)[pixel] == PixelMode::Merge || (*modes)[pixel] == PixelMode::Stop)));
  }
  bool stops(size_t pixel) const {
    return light_paths > 0 && !merge_everywhere && !records(pixel) && modes &&
           (*modes)[pixel] == PixelMode::Stop;
  }
  bool path_traces(size_t pixel) const {
    return !records(pixel) && (light_paths == 0 || (!merge_everywhere && modes &&
                                                    (*modes)[pixel] == PixelMode::PathTrace));
  }
  // Light-tracing splats land in the pixel (a pixel that path traces or maps photons alone
  // takes none).
  bool takes_splats(size_t pixel) const { return !path_traces(pixel) && !stops(pixel); }
  bool any_merge() const {
    return light_paths > 0 && (merge_everywhere || probe ||
                               (modes && std::any_of(modes->begin(), modes->end(), [](PixelMode m) {
                                  return m == PixelMode::Merge || m == PixelMode::Stop;
                                })));
  }
};

// Work counted in a probe iteration and, if measured, the seconds spent.
struct ProbeWork {
  double light_paths = 0, light_vertices = 0;
  double light_rays = 0;  // every bounce of the light subpaths (delta ones are not vertices)
  double camera_vertices = 0, nondelta_camera_vertices = 0;
  double connections = 0;  // light vertices a camera vertex was connected to
  double merge_queries = 0, photons = 0;
  // Of those, what photon mapping in the pixel would do: the camera vertices up to the first
  // one scattered through a non-delta lobe, and the query there with its photons.
  double stop_camera_vertices = 0, stop_merge_queries = 0, stop_photons = 0;
  double light_seconds = 0, camera_seconds = 0, connect_seconds = 0, merge_seconds = 0;
};

// The fraction of pixels in `mode` (0 for no pixels).
double fraction_of(const std::vector<PixelMode>& modes, PixelMode mode);

// Adds w's operation counts (not its seconds) to total.
void add_counts(ProbeWork& total, const ProbeWork& w);

struct PixelWork;  // adaptive_costs.h
struct CostModel;

class AdaptivePlan {
 public:
  AdaptivePlan() = default;
  // probe_stride: record one pixel in each probe_stride x probe_stride block in probes (0: the
  // stride for the image's size, kProbePixels).
  // force_mode >= 0: every pixel takes that PixelMode after each choice (experiments, tests).
  AdaptivePlan(int width, int height, bool measured_costs, bool probe_every_iteration = false,
               int probe_stride = 0, int force_mode = -1);
  // Cross-fits every candidate's per-pixel mix (choose()), also those that cannot win at the
  // mix's in-sample price, which only lowers it: tests of the cross-fitting. The choice is the
  // same either way; the report then gives every candidate's halves (otherwise null there).
  void price_every_candidate(bool on) { price_all_ = on; }
  // A probe renders its configuration (two connections per camera vertex, merging) and records
  // every contribution; both cost about twice what a chosen iteration costs, and on a large
  // image a probe is long beside the render (door-ajar at 640 x 480, 20 s, before this bound: 4
  // probes of 2.5 s took 48% of the time). So an image of more than kProbePixels pixels
  // probes about kProbePixels of them, one per block of the largest stride s with
  // s^2 kProbePixels <= pixels: the estimates pool over so many pixels that the choice does not
  // need more, and the other pixels render the last choice.
  static constexpr double kProbePixels = 40000;
  // After the first choice a sparse probe traces the chosen light paths (the probe's light
  // pass had cost up to 3x the chosen one: mirror-caustic at 640 x 480 chose half a light path
  // per pixel), at least this many and at most one per pixel.
  static constexpr double kSparseProbeLightPaths = 0.5;
  // Probes are iterations 0 and 1, then each after the iterations since the last one have cost
  // (predicted) what everything before it did (schedule_next_probe): with one cost per
  // iteration, iterations 3, 7, 15, 31, ... while the choice changes (settled_choices_).
  static constexpr int kFirstProbes = 2;
  static constexpr int kPoolRadius = 3;    // pixel statistics pooled over 7 x 7 (box_blur)
  static constexpr double kRelEps = 0.01;  // as the relMSE metric (image/metrics.h)
  // The quantile of pixel variances kept (shared_firefly_correction, check_last_choice).
  static constexpr double kWinsorize = 0.995;
  // What recording every contribution for every candidate adds to a probe's pixels (measured on
  // cornell-caustics 160x160, 1 thread: a probe 399 ms against 224 ms for vcm --connections 2,
  // docs/adaptive-vcm.md "What a probe costs").
  static constexpr double kProbeRecordingFactor = 1.78;
  // The most of the predicted time that the probes may take beyond the choice they replace.
  static constexpr double kMaxProbeShare = 0.1;
  // A choice repeats the last one where the candidate is the same and at most this share of
  // the pixels changed mode (settled_choices_, schedule_next_probe).
  static constexpr double kSettledChange = 0.05;
  // Rendering a choice shows variance the probes did not predict (unseen_sums_) where its
  // pooled relative variance exceeds the prediction by more than this factor: a prediction
  // from two probes falls below a third of the truth in about one pixel in 4000 (15 of 65536
  // in AdaptiveChoice.AFireflyThatNoProbeSawIsPricedIntoEveryCandidate), and a firefly of an
  // event no probe sampled exceeds it many times over.
  static constexpr double kUnseenFactor = 3.0;
  int probe_stride() const { return int(stride_); }
  // The image pixel of each grid pixel (those a probe records), in grid order: the pixels whose
  // segment moments finish_probe reads (SegmentMoments::reset).
  std::vector<size_t> grid_image_pixels() const;

  bool is_probe(uint32_t iteration) const;
  // The render's budget, before each probe is finished: iterations (a fixed --spp) or seconds
  // (--time) with the seconds spent so far; 0 where unknown. The probes' share of the time is
  // bounded by what the budget predicts (schedule_next_probe).
  void set_budget(double iterations, double seconds, double elapsed);
  // Before each probe is finished, with --time: the wall seconds of every probe so far (this
  // one included) and of the `iterations` iterations since the last probe (the last choice's).
  // The fixed model under-prices a probe beside the choice it replaces (the 14 scenes at their
  // own resolutions, 20 s, commit bb375eb: measured / predicted ratio of a probe's time to a
  // chosen iteration's 1.1-2.0 on 12 of them, water-caustic 0.95, sun-glass 3.0), so the probes
  // took 3-34% of a 20 s budget (median 15%) under a bound of kMaxProbeShare in the model's
  // units; with a budget in seconds the bound is also applied to these seconds
  // (probe_seconds_exceed_share). Not with --spp, whose probes must not depend on timing
  // (bit-identical images).
  void set_times(double probe_seconds, double segment_seconds, double segment_iterations);
  IterationPlan plan(uint32_t iteration) const;

  // Recording a probe. A pixel's estimate in a probe is the sum of its contributions F_i, each
  // from a technique t_i of the probe's counts n. Under candidate counts n' the same path has
  // the balance denominator Q'_i instead of Q_i; G_i = F_i Q_i / Q'_i is its contribution
  // under the candidate. Per candidate the pixel keeps
  //   R  = sum over contributions other than connections of G_i (n'_t / n_t)
  //   S0 = sum over connections to the pixel's own light path of G_i   (one per camera vertex)
  //   S1 = sum over connections to a light path drawn at random of G_i (one per camera vertex)
  //   D  = sum F_i^2 Q_i / Q'_i - (the squares of the G_i as they enter below)
  // A candidate with c' connections connects each camera vertex to the pixel's light path and
  // c' - 1 random ones: its pair of two vertices' connections shares a light path in 1 of c'^2
  // pairs, and a vertex's own c' connections are c'(c' - 1) independent pairs. Its second
  // moment is estimated by
  //   R^2 + 2 R (S0 + (c' - 1) S1) + S0^2 + (c' - 1) S1^2 + c'(c' - 1) S0 S1 + D
  // (each kind of pair at its count; Grittmann et al. 2022 scale one connection by c', which
  // counts every pair as sharing the light path and over-predicts many connections). The
  // diagonal is the proxy correction sum F^2 Q / Q' (exact for independent samples). For the
  // probe's own counts it is the sample's (sum F)^2. Light-tracing splats come first
  // (add_light_trace, in a fixed order), then the pixel's task continues from pixel_start()
  // with add() and hands the sums back with pixel_end().
  // Path tracing, then (light paths, connections) each without and with merging, then photon
  // mapping (PixelMode::Stop) per light-path factor.
  static constexpr size_t kCoreCandidates = 41, kStopCandidates = 4;
  static constexpr size_t kCandidates = kCoreCandidates + kStopCandidates;
  static constexpr int kProbeConnections = 2;  // the pixel's own light path and a random one
  enum class Share { None, OwnLightPath, RandomLightPath };  // of a connection
  // u: the Russian-roulette difference (roulette_diff_): sum over contributions of
  // G_i^2 (n'_t / n_t) - F_i^2 Q_i / Q'_i.
  // missing_pt: the sum of the contributions path tracing's techniques cannot make (a caustic
  // of a delta light seen on a diffuse surface): the energy it would miss (pt_missing_).
  struct CandidateSums {
    std::array<float, kCandidates> r{}, s0{}, s1{}, d{}, u{};
    float missing_pt = 0;
    float estimate = 0;  // the probe's own estimate of the pixel: the sum of its contributions
  };
  // radius: the probe's merge radius (the candidates' merge counts N' pi r^2).
  void begin_probe(float radius);
  // terms == nullptr: a path only one technique makes (the same F under every candidate).
  // share: which light path a connection went to (None for every other technique).
  void add(CandidateSums& sums, float value, const TechniqueTerms* terms, const MisCounts& counts,
           Share share = Share::None) const;
  void add_light_trace(size_t pixel, float value, const TechniqueTerms* terms,
                       const MisCounts& counts);
  CandidateSums pixel_start(size_t pixel) const;
  // camera_vertices: the pixel's camera subpath vertices in this probe (its share of the camera
  // pass's cost, pixel_vertices_).
  void pixel_end(size_t pixel, const CandidateSums& sums, double camera_vertices = 0);
  // After a probe: its work, and the pixel means of the iterations before it (empty after the
  // first; a mean from the probes alone makes a single sample look noiseless); re-optimises.
  // measured: per grid pixel (grid_image_pixels), the variance of one iteration's estimate over the
  // `iterations` iterations since the previous probe, which rendered the last choice
  // (SegmentMoments; empty if fewer than two): reported beside what was predicted for that
  // choice ("checks"). A few iterations measure a heavy tail low (13 scenes at 160 pixels wide,
  // 64 spp: measured / predicted 0.08-1.14 after 3 iterations, 0.80-1.26 after 31 except
  // water-caustic's 1.64), so a correction from them would keep a choice that happened to
  // render well; only what exceeds the prediction by far, where the camera pass alone makes
  // the estimate, is priced into every candidate alike (unseen_sums_). thread_seconds: what
  // those iterations took (wall seconds times threads), reported beside the cost predicted for
  // the choice.
  void finish_probe(const ProbeWork& work, const std::vector<float>& means,
                    const std::vector<double>& measured = {}, double iterations = 0,
                    double thread_seconds = 0);

  // "adaptive": the configuration, the history of choices (each with its candidate table and
  // costs), and the fractions of merging and of path-traced pixels in blocks of at most 64 x 64
  // cells ("merge_mask" and "path_trace_mask": width, height, row-major "fraction").
  void report(nlohmann::json& stats) const;
  const std::vector<PixelMode>& modes() const { return modes_; }

  // The weight of the probes' iterations in the image (ProbeFilm, probe_film.h): the mean over
  // grid pixels of the relative variance of one rendered iteration (the segments between probes,
  // as check_last_choice measured them, weighted by their iterations) over that of one probe
  // (the spread of the probes' own estimates), at most 1: the inverse-variance weight of the
  // probes against the rest, which minimises the image's summed relative variance for one
  // global weight. 1 before a segment of at least two iterations was measured. image_means: the
  // film's pixel means (image size). The variances come from the samples they weight, so the
  // combination is biased (a ratio estimator, as guided-pt's inverse-variance passes), and
  // consistent: the probes' share of the iterations vanishes as the render goes on.
  struct ProbeWeight {
    double weight = 1;
    double probe_relative_variance = 0, rendered_relative_variance = 0;  // per iteration
  };
  ProbeWeight probe_weight(const std::vector<float>& image_means) const;
  int probes() const { return probes_; }

  struct Candidate {
    float light_path_factor = 0;  // light paths / pixels
    int connections = 0;
    bool merge = false;  // from kCoreCandidates on: photon mapping (PixelMode::Stop)
  };
  static const std::vector<Candidate>& candidates();

 private:
  // Pixel p's relative variance per iteration under candidate j (times roulette_[j]), signed:
  // the second moment of a few probes minus the film's mean^2 is often negative where the
  // variance is small beside mean^2, and a clamp per pixel would bias it up by that noise
  // (relative_variances clamps after pooling).
  // half: the estimate from every probe, or from the even or odd ones (0, 2, ... or 1, 3, ...)
  // alone (cross-fitting, choose()).
  // square: the pixel's mean^2 that the second moment is reduced by (square()).
  enum class Half { All, Even, Odd };
  double relative_variance(size_t p, size_t j, double square, Half half = Half::All) const;
  // The mean^2 of pixel p that candidate j's variance subtracts from its second moment; the
  // same for every candidate with light paths (j > 0), so choose() computes those once per
  // pixel and half (squares()) instead of once per candidate.
  double square(size_t p, size_t j, const std::vector<float>& means, Half half = Half::All) const;
  std::vector<double> squares(const std::vector<float>& means, Half half) const;
  // Sets roulette_ from the sums so far (see roulette_diff_); squares: squares(means, All).
  void update_roulette_factors(const std::vector<float>& means, const std::vector<double>& squares);
  // Per pixel: what to add to every candidate's variance to winsorise the part they share.
  std::vector<double> shared_firefly_correction(const std::vector<float>& means, Half half,
                                                const std::vector<double>& squares) const;
  // Per-pixel values of up to kRowCandidates candidates under each half (All, Even, Odd).
  static constexpr size_t kRowCandidates = kStopCandidates;
  using Rows = std::array<std::array<std::vector<double>, kRowCandidates>, 3>;
  // out[h][k][p]: relative_variance of candidate first + k at grid pixel p under the h-th half,
  // for h in [h_begin, h_end) (squares[h]: squares(means, that half)). In one pass over the pixels,
  // whose moments lie side by side per pixel: a pass per candidate and half read each pixel's cache
  // line of the moments again (on material-testball, 384 x 216, the largest part of a choice's
  // time: `relative_variance` 12.8% of a two-probe render, whose choice was about 30%).
  void relative_variance_rows(size_t first, size_t count, size_t h_begin, size_t h_end,
                              const std::vector<float>& means,
                              const std::array<std::vector<double>, 3>& squares, Rows& out) const;
  // The same, plus correction[h] (shared_firefly_correction), pooled over neighbours and
  // clamped at 0, plus `unseen` (unseen_variance; empty: none).
  void relative_variances(size_t first, size_t count, size_t h_begin, size_t h_end,
                          const std::vector<float>& means,
                          const std::array<std::vector<double>, 3>& squares,
                          const std::array<std::vector<double>, 3>& correction,
                          const std::vector<double>& unseen, Rows& out) const;
  // Scores every candidate from the probes so far and takes the best (adaptive_choice.cpp).
  void choose(const std::vector<float>& means);
  // What one choice's candidates share, and the scoring of each (adaptive_choice.cpp).
  struct ChoiceInputs;
  // Adds the choice just taken to the history: its option (variant), costs and candidate table.
  void record_choice(const char* variant, const CostModel& t, nlohmann::json table);
  // Takes candidate j with one mode per grid pixel (chosen_, modes_, chosen_j_).
  void take_choice(size_t j, const std::vector<PixelMode>& grid_modes);
  // A probe's predicted microseconds per pixel after a choice (probe_cost_).
  void predict_probe_cost(const PixelWork& pw, const CostModel& t);
  // After a probe: when the next one comes (next_probe_), from the predicted costs of the
  // probes and of the choice.
  void schedule_next_probe();
  // The predicted cost of the budget's iterations after the probe at `probe` at cost `choice`
  // (infinite without a budget).
  double remaining_cost(uint64_t probe, double choice) const;
  // With a budget in seconds: whether another probe would take the probes' seconds beyond
  // kMaxProbeShare of it, in excess of the iterations of the choice (predicted cost `choice`)
  // that they stand in for. A chosen iteration's seconds are those the last segment took,
  // scaled by the model from its choice (predicted cost `segment_choice`) to this one, or
  // before any segment the last probe's at the model's ratio (`probe_cost`).
  bool probe_seconds_exceed_share(double choice, double segment_choice, double probe_cost) const;
  // The probes' bound: kMaxProbeShare, divided by k + 1 after a choice that repeated the one
  // before k times in a row (settled_choices_), as the wait for the next probe is multiplied.
  double probe_share() const { return kMaxProbeShare / double(1 + settled_choices_); }
  // Reports the last choice's measured and predicted relative variances (finish_probe;
  // adaptive_checks.cpp).
  void check_last_choice(const std::vector<double>& measured, double iterations,
                         double thread_seconds, const std::vector<float>& means);
  // Adds what the segment `measured` showed beyond the prediction to unseen_sums_; returns it
  // per grid pixel.
  // shrunk: the denominators of the segment's relative variances (denominators(means, &measured)).
  double add_unseen(const std::vector<double>& measured, double iterations,
                    const std::vector<double>& shrunk);

  size_t pixels_ = 0;  // the image's
  int width_ = 0, height_ = 0;
  // The probed pixels form a grid_w_ x grid_h_ image (grid_pixels_ pixels): every per-pixel
  // estimate below is of that grid, and a choice's modes_ take each image pixel's mode from the
  // grid pixel of its block.
  uint32_t stride_ = 1, offset_ = 0;
  int grid_w_ = 0, grid_h_ = 0;
  size_t grid_pixels_ = 0;
  size_t grid_index(size_t pixel) const {
    return size_t(pixel / width_ / stride_) * grid_w_ + (pixel % width_) / stride_;
  }
  template <typename T>
  std::vector<T> on_grid(const std::vector<T>& image) const;
  bool measured_ = false;
  bool probe_all_ = false;
  int force_mode_ = -1;
  bool price_all_ = false;  // price_every_candidate
  // pixels x candidates: the sum over probes of the second-moment estimates, as float24 (3 bytes
  // each, core/compact_float.h). 2^-16 relative rounding per addition: thousands of additions
  // (every probe, every light-tracing splat) stay far below the probes' sampling noise, and far
  // from where a sum stops growing. Not bfloat16: 2^-8 would lose a pixel's variance in the
  // rounding of its mean^2, and its sums would stall after a few hundred terms.
  std::vector<uint8_t> moments_;
  // The same sums over the odd probes alone (the even ones': moments_ minus these), to
  // cross-fit the per-pixel choice of modes (choose()).
  std::vector<uint8_t> moments_odd_;
  // Russian roulette. The balance weights leave it out (mis.h), so a contribution is
  // F = f / (Q rho_t), rho_t the survival probability of its own subpaths, and the proxy
  // F^2 Q / Q' estimates the integral of f^2 sum_t (n_t p_t / rho_t) / (Q Q'): the probe's
  // mixture of 1 / rho where the candidate has its own, sum_k (n'_k p_k / rho_k) / Q'^2. A
  // candidate without the probe's connections (short subpaths, rho near 1) leans on long
  // ones: with throughput roulette its variance was under-predicted by 7-16% (cornell,
  // point-room at 40 x 30; without roulette within 2%). The contributions of the candidate's
  // own techniques, G_i^2 (n'_t / n_t), estimate its diagonal without that error, but only
  // from the samples of those techniques (a heavy tail where they are poor). So per pixel and
  // candidate this keeps their difference from the proxy (float24, as moments_), and each
  // choice scales candidate j's relative variances by roulette_[j] = 1 + the mean over the
  // pixels of that difference over the relative variance, both pooled over 7 x 7 and the ratio
  // at least -1, the factor at least 1: the proxy's spatial detail, the own techniques' level
  // (update_roulette_factors).
  std::vector<uint8_t> roulette_diff_;
  // Per grid pixel: its camera vertices summed over the probes. The camera-vertex parts of a
  // mode's price scale per pixel with them (relative to the image's mean, pooled as the
  // variances are: pixel_cost_weights): a pixel that sees the sky costs less than one on a
  // glass sphere. An image-wide price per mode underestimated a mix that path traces the cheap
  // pixels (material-spheres, 800 x 450, 20 s, seeds 2 and 3: measured / predicted cost of the
  // choice 1.05-1.21 with it, 0.98-1.11 with these weights).
  std::vector<float> pixel_vertices_;
  std::vector<double> pixel_cost_weights() const;
  // Per grid pixel: the energy path tracing misses (CandidateSums::missing_pt), summed over the
  // probes. Its mean is the bias of path tracing's estimate there, and its square divided by
  // (mean^2 + 0.01) what that bias adds to the relative MSE however long pt renders. Where the
  // budget is known, the candidate without light paths (and a pixel that path traces alone)
  // is priced with that bias instead of being ruled out (path_tracing_bias_weight): a faint
  // caustic of a delta light can cost less in error than the light paths that find it cost in
  // noise elsewhere (material-spheres and sun-glass at 20 s: `pt` beat every configuration with
  // light paths by 1.45x and 1.81x). A bright caustic's bias outweighs that; and as the budget
  // grows, so does the weight, so the choice converges to the unbiased one.
  std::vector<float> pt_missing_;
  // This probe's part of pt_missing_ (zeroed by begin_probe), and per grid pixel the sum over
  // the probes of the square of each probe's missed energy pooled over the pixel's 7 x 7 window
  // (finish_probe): with pt_missing_ pooled the same way, the unbiased estimate of the pooled
  // bias^2 (path_tracing_bias).
  std::vector<float> probe_missing_;
  std::vector<double> pooled_missing_squares_;
  // The square of a pixel's mean that its variance subtracts from the candidates' second
  // moments, unbiased: per grid pixel the sum over probes of the film's mean before the probe
  // times the probe's own estimate (independent: different iterations), and how many probes
  // added to it. The square of the film's mean itself exceeds mu^2 by that mean's variance,
  // which at the first choice (a film of one iteration, the first probe) is a whole iteration's:
  // every candidate's variance came out too low by it (docs/adaptive-vcm.md, "The first
  // choice's bias"). Without a film before any probe yet, the film's mean squared stands.
  std::vector<float> probe_estimate_;  // this probe's (pixel_end), per grid pixel
  std::vector<float> light_estimate_;  // this probe's light-tracing splats (add_light_trace)
  std::vector<double> mean_square_sums_;
  int mean_square_probes_ = 0;
  // Per grid pixel, over every probe: the sum of the probe's own estimates and of their squares
  // (the variance of one probe's estimate, for denominators()).
  std::vector<double> estimate_sums_, estimate_square_sums_;
  // The iteration of the probe just finished (finish_probe, before schedule_next_probe): the
  // first probes come at 0 and 1, then at next_probe_ (probe_all_: every iteration). It is also
  // the count of the film's iterations before that probe, its means' sample count.
  uint64_t probe_iteration() const {
    return probe_all_ || probes_ <= kFirstProbes ? uint64_t(probes_ - 1) : next_probe_;
  }
  // Per grid pixel: the relative variance's denominator mu^2 + 0.01, set by choose() and read
  // while it chooses (denominator_). The film's mean m holds a few iterations at the first
  // choices (one at the first), and 1 / (m^2 + 0.01) of so noisy a mean is far above
  // 1 / (mu^2 + 0.01) on average (most in the noisiest pixels, where m mostly falls below mu):
  // after 2 probes on point-room every prediction was 1.47-1.69x what rendering showed (docs/
  // adaptive-vcm.md, "The first choice's bias"). So m is shrunk toward its 7 x 7 pooled mean M:
  // m' = M + max(0, 1 - c^2 s^2 / (n (m - M)^2)) (m - M), the positive-part James-Stein factor
  // with c = kShrinkSigmas standard errors, s^2 the variance of one probe's estimate there (the
  // larger of the pixel's own over the probes and its 7 x 7 pooled value) and n the film's
  // iterations. A pixel that stands out from its neighbours by more than that (an
  // emitter's edge) keeps its own mean, and as n grows every pixel does. With `rendered` (the
  // per-iteration variance that a segment of the film showed, check_last_choice) s^2 is at
  // least that: a firefly, which raises its pixel's mean as much as its variance, is shrunk
  // away.
  std::vector<double> denominators(const std::vector<float>& means,
                                   const std::vector<double>* rendered = nullptr) const;
  std::vector<double> denominator_;
  // mean^2 for pixel p whose film mean is m: mean_square_sums_ / mean_square_probes_, or m^2.
  double mean_square(size_t p, double m) const;
  // The variance of one probe's estimate of grid pixel p, from the spread of the probes' own
  // estimates (unbiased; it may come out negative by rounding). Needs two probes.
  double probe_estimate_variance(size_t p) const {
    const double k = double(probes_);
    return (estimate_square_sums_[p] - estimate_sums_[p] * estimate_sums_[p] / k) / (k - 1);
  }
  // Per grid pixel, pooled as the variances are: what path tracing's bias adds to its variance
  // per iteration, the relative bias^2 times the weight that turns it into a per-iteration
  // variance, the iterations path tracing would render in the budget
  // (path_tracing_bias_weight). Without a budget (an infinite weight) any missed energy rules
  // it out, as every candidate that misses energy is.
  // relative_sum: the relative bias^2 summed over the pixels (unweighted, for the report).
  std::vector<double> path_tracing_bias(double weight, double* relative_sum) const;
  double path_tracing_bias_weight(const PixelWork& pw, const CostModel& t) const;
  double bias_iterations_ = 0;    // the last choice's weight, for the report
  double relative_bias_sum_ = 0;  // and path tracing's relative bias^2 summed over pixels
  std::array<double, kCandidates> roulette_;
  // pixels x (R, D, U) x candidates: this probe's light-tracing sums, in bfloat16 while the
  // probe renders; the pixel's camera pass starts from them (pixel_start), so they reach the
  // moments with its own. A pixel gets a few splats per probe, so each sum keeps about 2^-8
  // relative precision, far below the sampling noise of one probe's second-moment estimate.
  // (Adding each splat's D and U to the float24 moments at once, in the light pass's serial
  // stage, was a quarter of a probe's time on cornell-caustics.)
  static constexpr size_t kLightSums = 3;
  std::vector<uint16_t> light_sums_;
  std::vector<float> light_missing_pt_;  // per grid pixel: the splats' missing_pt
  // The candidates' counts per class for this probe's radius (structure of arrays).
  struct CountTable {
    std::array<float, kCandidates> emitter{}, light_trace{}, connect{}, merge{};
    const std::array<float, kCandidates>& of(TechniqueClass c) const {
      return c == TechniqueClass::Emitter      ? emitter
             : c == TechniqueClass::LightTrace ? light_trace
             : c == TechniqueClass::Connect    ? connect
                                               : merge;
    }
  } table_;
  int probes_ = 0;
  // The probes' schedule (is_probe): the iteration of the next probe after the first two, the
  // iterations probed so far from the second probe on (iteration 0 is always one), and the
  // predicted microseconds per pixel of every iteration up to the last probe and of the last
  // choice (schedule_next_probe).
  uint64_t next_probe_ = kFirstProbes;
  std::vector<uint64_t> probe_iterations_;
  double spent_cost_ = 0, last_choice_cost_ = 0, probe_excess_ = 0;
  double probe_cost_ = 0;    // a probe's predicted microseconds per pixel (choose)
  int settled_choices_ = 0;  // how many choices in a row repeated the one before (take_choice)
  double budget_iterations_ = 0, budget_seconds_ = 0, elapsed_seconds_ = 0;  // set_budget
  // set_times: the probes' wall seconds, the last probe's, and the last segment's per iteration
  // (0: no iteration since the previous probe).
  double probe_seconds_ = 0, last_probe_seconds_ = 0, segment_iteration_seconds_ = 0;
  ProbeWork work_;  // summed over probes
  std::vector<PixelMode> modes_;
  IterationPlan chosen_;
  // The last choice: its candidate (the index of its entry without merging; 0: path tracing;
  // kCandidates: none yet) and per pixel the pooled relative variance predicted for it (of the
  // mode the pixel took), to check against what rendering it shows.
  size_t chosen_j_ = kCandidates;
  std::vector<double> chosen_variance_;
  // Per grid pixel: the pooled relative variance per iteration that rendering a choice showed
  // beyond its prediction where the pixel saw the camera pass's estimate alone (path tracing,
  // photon mapping), and only where more than kUnseenFactor times it (check_last_choice),
  // summed over those segments weighted by their iterations; and those iterations. Every
  // candidate's variance there takes their mean (unseen_variance): the variance of events no
  // probe sampled (a camera path that reaches a small light through specular bounces, on
  // mirror-caustic), which each iteration's camera paths make whatever its configuration.
  std::vector<double> unseen_sums_, unseen_iterations_;
  // The mean of unseen_sums_ per grid pixel (empty before any segment).
  std::vector<double> unseen_variance() const;
  double chosen_cost_ = 0;              // its predicted microseconds per pixel and iteration
  std::vector<nlohmann::json> checks_;  // one per check_last_choice(), for the report
  // Over the measured segments: their iterations times the mean over grid pixels of one
  // iteration's relative variance, and those iterations (probe_weight).
  double rendered_relative_sum_ = 0, rendered_iterations_ = 0;
  std::vector<nlohmann::json> history_;
};

}  // namespace caustica::bidir
