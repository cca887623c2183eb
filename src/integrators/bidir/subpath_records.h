// What one guided subpath of guided-bpt / guided-vcm teaches the field that guides it, when the
// fields learn from the subpaths themselves (GuidingSettings::RadianceRecords and
// ImportanceRecords): Müller et al. 2017, sec. 3.2, as guided-pt records.
//
// A guided vertex j sampled wi_j with density pdf_j and carries the throughput beta_j after its
// scattering. Whatever the subpath's running sum gains after that is beta_j times an estimate of
// what arrives at j along wi_j, so the vertex's record is that estimate times |cos| / pdf_j:
// summed over a directional quadrant, an estimate of the flux (times the cosine, as photons
// carry it) arriving through it.
//  - camera subpaths: the sum is the pixel's estimate (PixelAccumulator::sum: emitter hits, next
//    event estimation, connections and merges at later vertices, each MIS-weighted), and the
//    record is incident radiance;
//  - light subpaths: the sum is what the later vertices' connections to the lens found,
//    unweighted, and the record is incident importance.
// The gains are read off the running sum, so the techniques need not know about guiding.
#pragma once

#include <algorithm>
#include <cmath>

#include "core/arena.h"
#include "core/rgb.h"
#include "core/vec.h"

namespace caustica::bidir {

class SubpathRecords {
 public:
  struct Vertex {
    Vec3 p, ng, wi;
    int depth = 0;
    float per_pdf = 0;                  // |cos| to the shading normal over the sampling density
    Rgb weight;                         // f |cos| / pdf
    float bsdf_pdf = 0, guide_pdf = 0;  // the mixture's two densities of wi (guide 0: none)
    Rgb beta_after;                     // the throughput including this vertex's f |cos| / pdf
    Rgb incident;                       // the radiance estimate arriving along wi
  };

  SubpathRecords(ScratchArena& arena, int max_vertices)
      : vertices_(static_cast<Vertex*>(
            arena.allocate(sizeof(Vertex) * size_t(std::max(max_vertices, 1)), alignof(Vertex)))),
        capacity_(std::max(max_vertices, 1)) {}

  // The pixel's estimate is now sum: what it gained since the last call arrived at every vertex
  // recorded so far.
  void gained(Rgb sum) {
    const Rgb c = sum - seen_;
    seen_ = sum;
    if (c.is_black()) return;
    for (int j = 0; j < count_; ++j)
      for (int ch = 0; ch < 3; ++ch)
        if (vertices_[j].beta_after[ch] > 0)
          vertices_[j].incident[ch] += c[ch] / vertices_[j].beta_after[ch];
  }
  // Call gained() first, so that earlier gains do not reach this vertex.
  void add(const Vertex& v) {
    if (count_ == capacity_ || !(v.per_pdf > 0) || !std::isfinite(v.per_pdf)) return;
    vertices_[count_] = v;
    vertices_[count_++].incident = Rgb(0.f);
  }
  // push(vertex, radiance, product) for every vertex, in order: the record's L |cos| / pdf and
  // the luminance of f |cos| L / pdf (the BSDF selection's target, selection_optimizer.h). Those
  // that received nothing too (0, 0), since every guided vertex counts for the spatial split
  // rule (Müller et al. 2017: "path vertices"); only 1 in 10 received something on door-ajar.
  template <typename Push>
  void finish(Rgb sum, Push&& push) {
    gained(sum);
    for (int j = 0; j < count_; ++j) {
      const Vertex& v = vertices_[j];
      const float radiance = v.incident.luminance() * v.per_pdf;
      const float product = (v.weight * v.incident).luminance();
      const bool finite = std::isfinite(radiance) && std::isfinite(product);
      push(v, finite ? radiance : 0.f, finite ? product : 0.f);
    }
  }

 private:
  Vertex* vertices_;
  int capacity_;
  int count_ = 0;
  Rgb seen_{0.f};
};

}  // namespace caustica::bidir
