// The probabilities with which guided-bpt and guided-vcm take a vertex's deterministic
// techniques: next event estimation, the lens connection of a light vertex, and the connection
// of a light vertex to a camera vertex. On door-ajar (320x240, vcm) 99% of the light samples,
// 97% of the connections and 99.6% of the lens connections were blocked, and together they
// took about 40% of the render's time. Like guided-pt's next event probability
// (guiding/guiding_field.h, add_technique_counts), each is learned per spatial leaf of the
// radiance field during training: a leaf that took at least GuidingField::kNeeEvidence samples
// of a technique and saw nothing through any gets GuidingSettings::nee_floor, any other 1 (for
// connections "nothing" is at most GuidingSettings::connection_visible_share of them: light
// through a gap is seen from everywhere along its sight lines). A technique's probabilities
// apply only while its reduced leaves hold a real share of its attempts
// (BidirGuiding::kMinReducedShare): elsewhere the lookups would cost more than they save.
//
// A technique's probability belongs to the vertex that ends its light subpath (for next event
// estimation: the camera vertex that samples the light), on the side of that vertex's
// geometric normal toward where it leaves: for a connection or lens connection the side of
// the camera-side vertex (or the lens), for next event estimation the side of the light point.
// So it is a function of the path alone, which the MIS sums need (mis.h, MisRules::scale_vcm):
// both subpaths see the same count for every technique, and the weights still sum to one.
#pragma once

#include <cstdint>

#include "core/vec.h"
#include "guiding/guiding_field.h"
#include "integrators/bidir/vertex_guides.h"

namespace caustica::bidir {

struct VertexProbabilities {
  static constexpr uint32_t kNoLeaf = ~0u;
  const BidirGuiding* fields = nullptr;  // nullptr: every probability is 1, nothing is counted
  Vec3 p;
  Vec3 ng;  // geometric normal
  // The vertex's guides, whose radiance leaves (looked up for sampling at camera vertices)
  // are these leaves too: nullptr, or guides at the same point and normal.
  const VertexGuides* guides = nullptr;
  mutable uint32_t leaf[2] = {kNoLeaf, kNoLeaf};  // per side of ng, looked up once

  explicit operator bool() const { return fields != nullptr; }
  // The radiance field's leaf on the side of w (only with fields).
  uint32_t leaf_toward(Vec3 w) const;
  // The probability of technique t leaving the vertex toward w.
  float of(GuidingField::Technique t, Vec3 w) const;
};

}  // namespace caustica::bidir
