#include "integrators/bidir/bidir_guiding.h"

#include <tbb/parallel_for.h>

#include <algorithm>

#include "core/rng.h"
#include "integrators/guide_views.h"
#include "integrators/schedule_report.h"
#include "scene/scene.h"

namespace caustica::bidir {

namespace {

constexpr uint64_t kKeysPerPixel = 256;  // camera records: pixel * 256 + depth (depth <= 255)
constexpr float kDefaultBsdfFraction = 0.5f;

}  // namespace

void BidirGuiding::prepare(const Bounds3& bounds, GuidingSettings settings, uint64_t pixels,
                           int spp, double seconds) {
  enabled_ = true;
  count_techniques_ = settings.nee_floor < 1;
  for (bool& r : reduced_) r = false;
  for (TechniqueCounts& counts : technique_counts_)
    for (std::vector<uint32_t>& c : counts) c.clear();
  guide_camera_ = settings.guide_camera_paths;
  guide_light_ = settings.guide_light_paths;
  using Records = GuidingSettings::RadianceRecords;
  radiance_from_photons_ = settings.radiance_records != Records::CameraPaths;
  radiance_from_camera_ = settings.radiance_records != Records::Photons;
  using Importance = GuidingSettings::ImportanceRecords;
  importance_from_camera_ = settings.importance_records != Importance::LightPaths;
  importance_from_light_ = settings.importance_records != Importance::Importons;
  if (guide_camera_ && guide_light_) settings.max_bytes /= 2;
  // The BSDF selection probability is learned (negative) only from the camera subpaths'
  // records, which carry the product f |cos| L_i; photons and importance records do not.
  GuidingSettings fixed = settings;
  if (fixed.bsdf_fraction < 0) fixed.bsdf_fraction = kDefaultBsdfFraction;
  radiance_ = GuidingField(bounds, radiance_from_camera_ ? settings : fixed, /*sided=*/true);
  importance_ = GuidingField(bounds, importance_from_light_ ? settings : fixed, /*sided=*/true);
  schedule_ = TrainingSchedule(spp, seconds);
  iteration_ = 0;
  // About four camera vertices per path: one pixel in k keeps the records under kMaxRecords.
  camera_stride_ = std::max<uint64_t>(1, (4 * pixels + kMaxRecords - 1) / kMaxRecords);
  pixels_ = pixels;
  radiance_records_ = importance_records_ = 0;
}

void BidirGuiding::begin_iteration(uint32_t iteration, double elapsed, uint64_t light_paths) {
  iteration_ = iteration;
  if (iteration == 0) schedule_.starts_pass(0, elapsed);
  if (light_paths == 0) light_paths = pixels_;
  // About three guided vertices per light subpath.
  light_stride_ = std::max<uint64_t>(1, (3 * light_paths + kMaxRecords - 1) / kMaxRecords);
  if (schedule_.learning() && guide_light_ && importance_from_light_)
    light_records_.begin_iteration(light_paths / light_stride_ + 1);
  if (schedule_.learning() && importance_from_camera_)
    camera_records_.begin_iteration(pixels_ / camera_stride_ + 1);
  if (schedule_.learning() && guide_camera_ && radiance_from_camera_)
    camera_radiance_records_.begin_iteration(pixels_ / camera_stride_ + 1);
}

bool BidirGuiding::end_pass_after(uint32_t iteration, double elapsed,
                                  const InverseVarianceCombiner& passes) {
  if (!schedule_.starts_pass(iteration + 1, elapsed)) return false;
  const bool learned = schedule_.ended_learning();
  const int k = schedule_.ended_training_pass();
  const std::vector<InverseVarianceCombiner::Pass> all = passes.passes();
  const InverseVarianceCombiner::Pass ended =
      all.empty() ? InverseVarianceCombiner::Pass{0, -1} : all.back();
  schedule_.end_pass(ended.variance, ended.variance_error);
  if (learned) {
    radiance_.end_pass(k);
    importance_.end_pass(k);
    // A technique is taken at its learned probabilities only where that pays for the lookups
    // (a spatial descent at most light vertices): when the reduced leaves hold a real share of
    // its attempts (veach-bidir: 0.01% of connections, 3.7% of lens connections).
    for (int t = 0; t < GuidingField::kTechniques; ++t)
      reduced_[t] = radiance_.reduced_attempt_share(GuidingField::Technique(t)) >= kMinReducedShare;
  }
  return true;
}

void BidirGuiding::count_technique(GuidingField::Technique t, uint32_t leaf, bool seen) const {
  std::vector<uint32_t>& counts = technique_counts_.local()[t];
  if (counts.size() != 2 * radiance_.leaf_count()) counts.assign(2 * radiance_.leaf_count(), 0);
  ++counts[2 * leaf];
  counts[2 * leaf + 1] += seen;
}

uint32_t VertexProbabilities::leaf_toward(Vec3 w) const {
  const int side = VertexGuides::side_of(ng, w);
  if (leaf[side] == kNoLeaf) {
    if (guides) {
      guides->guide(TransportMode::Radiance, w);  // resolves the side's leaf, once
      leaf[side] = guides->leaf[int(TransportMode::Radiance)][side];
    }
    // Guides marked resolved without a lookup (as tests set them) hold no leaf.
    if (leaf[side] == kNoLeaf) leaf[side] = fields->probability_leaf(p, side ? -ng : ng);
  }
  return leaf[side];
}

float VertexProbabilities::of(GuidingField::Technique t, Vec3 w) const {
  if (!fields || !fields->reduces(t)) return 1.f;
  return fields->radiance().guide(leaf_toward(w)).probability[t];
}

// As guided-pt's (guidable_bsdf, guided_mixture.h): layered BSDFs are guided whatever their
// coat (sample_guided weighs their walks), other BSDFs only without specular lobes.
bool BidirGuiding::guidable(const Bsdf& bsdf) {
  return !bsdf.is_delta() && (bsdf.stochastic() || !is_specular(bsdf.flags()));
}

VertexGuides BidirGuiding::at(Vec3 p, Vec3 ng, const Bsdf& bsdf) const {
  VertexGuides g;
  if (!enabled_ || !schedule_.guided() || !guidable(bsdf)) return g;
  g.fields = this;
  g.p = p;
  g.n = ng;
  return g;
}

void VertexGuides::resolve(TransportMode mode, int side) const {
  const int front = GuidingField::side_class(n);
  const int c = side ? front ^ 1 : front;  // -n: the same axis, the other sign
  // A subpath that is not guided keeps no guide (its densities are the BSDF's).
  const bool radiance = mode == TransportMode::Radiance;
  if (radiance ? fields->guide_camera_ : fields->guide_light_) {
    const GuidingField& field = radiance ? fields->radiance_ : fields->importance_;
    leaf[int(mode)][side] = field.leaf_at(p, c);
    const GuidingField::Guide& g = field.guide(leaf[int(mode)][side]);
    guides[int(mode)][side] = g.distribution;
    bsdf[int(mode)][side] = g.bsdf_fraction;
  }
  resolved |= uint8_t(1u << (2 * int(mode) + side));
}

GuidingRecord BidirGuiding::record_at(const GuidingField& field, uint64_t key, Vec3 p, Vec3 ng,
                                      Vec3 wo, float value) const {
  const int side = GuidingField::side_class(face_forward(ng, wo));
  GuidingRecord r;
  r.key = key;
  r.leaf = field.leaf_at(p, side);
  if (field.settings().filter) {
    // The spatial box filter's jitter, hashed from the key (a thread-independent sample).
    const uint64_t h = mix_bits(key ^ (uint64_t(iteration_) << 40) ^ 0x5bd1e995ull);
    const Vec3 u(float(h & 0xfffff) * 0x1p-20f, float((h >> 20) & 0xfffff) * 0x1p-20f,
                 float((h >> 40) & 0xfffff) * 0x1p-20f);
    r.leaf = field.jittered_leaf(p, r.leaf, u, side);
  }
  r.square = direction_to_square(wo);
  r.radiance = value;
  r.product = 0;
  r.guide_pdf = 0;  // no selection gradient: the BSDF fraction is fixed
  return r;
}

void BidirGuiding::record_camera_vertex(uint64_t pixel, int depth, Vec3 p, Vec3 ng, Vec3 wo,
                                        Rgb beta) const {
  const float value = beta.luminance();
  if (!(value > 0) || !std::isfinite(value)) return;
  camera_records_.writer(pixel / camera_stride_)
      .push(record_at(importance_, pixel * kKeysPerPixel + uint64_t(depth), p, ng, wo,
                      value * float(camera_stride_)));
}

void BidirGuiding::record_subpath_vertex(const GuidingField& field, const PixelRecords& records,
                                         uint64_t subpath, uint64_t stride,
                                         const SubpathRecords::Vertex& v, float value,
                                         float product) const {
  GuidingRecord r = record_at(field, subpath * kKeysPerPixel + uint64_t(v.depth), v.p, v.ng, v.wi,
                              value * float(stride));
  // The BSDF selection learns where a guide sampled (guide_pdf > 0) and something was found.
  r.product = product * float(stride);
  r.bsdf_pdf = v.bsdf_pdf;
  r.guide_pdf = v.guide_pdf;
  records.writer(subpath / stride).push(r);
}

void BidirGuiding::learn(GuidingField& field, std::span<const std::span<const GuidingRecord>> runs,
                         uint64_t stride) {
  // Every record stands for `stride` vertices in the split rule's counts (and its value was
  // scaled by the stride when it was made).
  std::vector<uint32_t> counts(field.leaf_count(), 0);
  for (std::span<const GuidingRecord> run : runs)
    for (const GuidingRecord& r : run) counts[r.leaf] += uint32_t(stride);
  field.add_vertex_counts(counts);
  field.splat(runs);
}

void BidirGuiding::end_iteration(const Scene& scene,
                                 const std::vector<LightVertex>& light_vertices) {
  if (!schedule_.learning()) return;
  // The threads' technique counts are integers: their sum does not depend on the threads.
  for (TechniqueCounts& counts : technique_counts_) {
    for (int t = 0; t < GuidingField::kTechniques; ++t) {
      if (counts[t].size() != 2 * radiance_.leaf_count()) continue;
      radiance_.add_technique_counts(GuidingField::Technique(t), counts[t]);
      std::fill(counts[t].begin(), counts[t].end(), 0);
    }
  }
  if (guide_light_ && importance_from_light_) {
    importance_records_ += light_records_.size();
    learn(importance_, light_records_.runs(), light_stride_);
  }
  if (guide_light_ && importance_from_camera_) {
    importance_records_ += camera_records_.size();
    learn(importance_, camera_records_.runs(), camera_stride_);
  }
  if (!guide_camera_) return;
  if (radiance_from_camera_) {
    radiance_records_ += camera_radiance_records_.size();
    learn(radiance_, camera_radiance_records_.runs(), camera_stride_);
  }
  if (!radiance_from_photons_) return;
  // Radiance from the light vertices: every k-th one, shifted by the iteration.
  const size_t n = light_vertices.size();
  const size_t stride = std::max<size_t>(1, (n + kMaxRecords - 1) / kMaxRecords);
  const size_t first = n ? size_t(iteration_) % stride : 0;
  const size_t count = first < n ? (n - first + stride - 1) / stride : 0;
  merged_.resize(count);
  tbb::parallel_for(size_t(0), count, [&](size_t j) {
    const size_t i = first + j * stride;
    const LightVertexData v = unpack_light_vertex(light_vertices[i]);
    const Vec3 ng = scene.interaction_at(v.primitive, v.p, v.wo).ng;
    merged_[j] = record_at(radiance_, i, v.p, ng, v.wo, v.throughput.luminance() * float(stride));
  });
  std::erase_if(merged_, [](const GuidingRecord& r) {
    return !(r.radiance > 0) || !std::isfinite(r.radiance);
  });
  radiance_records_ += merged_.size();
  const std::span<const GuidingRecord> light_run(merged_);
  learn(radiance_, {&light_run, 1}, stride);
}

void BidirGuiding::make_views(const Scene& scene) {
  views_ = nlohmann::json::object();
  if (guide_camera_)
    views_["radiance"] = guide_views(
        scene, [&](Vec3 p, int side) { return &radiance_.sampling(radiance_.leaf_at(p, side)); });
  if (guide_light_)
    views_["importance"] = guide_views(scene, [&](Vec3 p, int side) {
      return &importance_.sampling(importance_.leaf_at(p, side));
    });
}

void BidirGuiding::report(nlohmann::json& stats) const {
  nlohmann::json g;
  report_schedule(schedule_, g);
  g["radiance_spatial_leaves"] = radiance_.leaf_count();
  g["importance_spatial_leaves"] = importance_.leaf_count();
  g["radiance_guiding_bytes"] = radiance_.memory_bytes();
  g["importance_guiding_bytes"] = importance_.memory_bytes();
  g["guiding_bytes"] = radiance_.memory_bytes() + importance_.memory_bytes();
  g["guiding_max_bytes"] = (guide_camera_ && guide_light_ ? 2 : 1) * radiance_.settings().max_bytes;
  g["guided_subpaths"] = guide_camera_ && guide_light_ ? "both"
                         : guide_camera_               ? "camera"
                                                       : "light";
  g["nee_reduced_leaves"] = radiance_.reduced_leaves(GuidingField::kNextEvent);
  g["lens_connection_reduced_leaves"] = radiance_.reduced_leaves(GuidingField::kLensConnection);
  g["connection_reduced_leaves"] = radiance_.reduced_leaves(GuidingField::kConnection);
  g["technique_floor"] = radiance_.settings().nee_floor;
  // Of each technique's attempts in the last training pass, the share in reduced leaves, and
  // whether its probabilities apply (that share at least kMinReducedShare).
  for (const auto& [name, t] : {std::pair{"nee", GuidingField::kNextEvent},
                                std::pair{"lens_connection", GuidingField::kLensConnection},
                                std::pair{"connection", GuidingField::kConnection}}) {
    g[std::string(name) + "_reduced_attempt_share"] = radiance_.reduced_attempt_share(t);
    g[std::string(name) + "_probabilities_applied"] = reduced_[t];
  }
  g["radiance_records"] = radiance_records_;
  g["radiance_learned_from"] = radiance_from_photons_ && radiance_from_camera_ ? "both"
                               : radiance_from_camera_                         ? "camera"
                                                                               : "photons";
  g["importance_records"] = importance_records_;
  g["bsdf_fraction"] = importance_.settings().bsdf_fraction;
  g["radiance_bsdf_fraction_mean"] = radiance_.mean_bsdf_fraction();
  g["importance_bsdf_fraction_mean"] = importance_.mean_bsdf_fraction();
  g["importance_learned_from"] = importance_from_light_ && importance_from_camera_ ? "both"
                                 : importance_from_light_                          ? "light"
                                                                                   : "importons";
  if (!views_.is_null()) g["views"] = views_;
  stats["guiding"] = g;
}

}  // namespace caustica::bidir
