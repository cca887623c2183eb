// The knobs of path guiding (Müller et al. 2017, "Practical Path Guiding for Efficient
// Light-Transport Simulation", with the improvements of Müller 2019, "Practical Path Guiding in
// Production", SIGGRAPH course "Path Guiding in Production"). The command line sets them with
// the --guiding-* options; the defaults are the papers'.
#pragma once

#include <cstddef>

namespace caustica {

struct GuidingSettings {
  // c of the spatial split rule: a leaf that recorded more than c sqrt(2^k) path vertices in
  // training pass k (2^k samples per pixel) is split (Müller et al. 2017, sec. 3.4). Müller's
  // 12000 would leave more records per leaf; 4000 was 1.07x better for guided-pt at equal time on
  // door-ajar (320x240, 60 s, three seeds: relMSE 0.310-0.326 against 0.334-0.345, at rho 0.01).
  double spatial_threshold = 4000;
  // A directional quadrant is refined where its share of the leaf's energy exceeds rho (Müller:
  // 0.01). With a third of Müller's records per leaf the shares are noisier: at 0.01 one bright
  // record carves a narrow peak that the next pass samples. guided-pt on door-ajar (320x240,
  // 20 s, 2 threads, seeds 1 and 2): relMSE 0.74 and 0.85 at 0.05 against 0.99 and 1.01 at 0.01
  // (seed 1 at 0.03: 0.77; 0.06: 0.72; 0.12: 0.85). guided-vcm at 64 spp (seed 1): 0.663 with
  // (4000, 0.05) against 0.764 with Müller's (12000, 0.01); vcm 0.797.
  double rho = 0.05;
  int max_quadtree_depth = 20;
  // The share of a leaf's learned energy that its next training pass starts from (Müller 2017
  // discards it: 0). A training pass's records are unbiased flux estimates whatever
  // distribution sampled them, so carrying them on lets pass k's distribution learn from the
  // passes before it too (with carry 1, from all of them, each by its sample count; at 0.5
  // pass k - 1 weighs a quarter of pass k, pass k - 2 a sixteenth; the energy of a leaf that
  // splits goes half to each child). door-ajar 320x240, 64 spp, seeds 1 and 2, relMSE:
  // guided-pt 4.07 / 3.97 at 0, 3.65 / 3.72 at 0.5, 3.76 / 3.67 at 1; guided-vcm (48 spp)
  // 0.615 / 0.637 at 0, 0.607 / - at 0.5, 0.620 / 0.617 at 1.
  double carry = 0.5;
  // The memory cap: the whole structure (spatial tree, leaves, directional quadtrees) stays
  // under this many bytes; splits and refinements that would exceed it are not done.
  size_t max_bytes = size_t(32) << 20;
  // Filtered splatting (Müller 2019): each record is spread over a box the size of its spatial
  // leaf and of its directional leaf, both stochastically (a position jittered within the box;
  // in expectation the box filter, see DirectionalQuadtree::record_jittered).
  bool filter = true;
  // The probability of sampling the BSDF rather than the learned distribution: learned per
  // spatial leaf by Adam on the KL divergence gradient (Müller 2019) when negative, else fixed.
  float bsdf_fraction = -1;
  // What the directional distributions learn: the incident radiance (Mueller et al. 2017), or
  // the incident radiance times |cos| to the vertex's shading normal. The latter is the product
  // with the cosine at no cost: a leaf's points share a side class, so their normals are alike,
  // and on a diffuse surface it is the product with the whole BSDF.
  bool cosine_product = true;
  // guided-bpt / guided-vcm: which subpaths are guided (the other samples its BSDF alone, and
  // its field is neither learned nor looked up). door-ajar 320x240, 48 spp, 2 threads, relMSE
  // per sample: camera 0.86, light 1.04, both 0.80 (vcm 1.04).
  bool guide_camera_paths = true, guide_light_paths = true;
  // guided-bpt / guided-vcm: what the radiance field (which guides camera subpaths) learns from:
  // the light vertices (photons: the flux arriving at each, Vorba et al. 2014), the camera
  // subpaths themselves (the radiance each guided camera vertex received along its sampled
  // direction through every later technique, over that direction's density: Mueller et al.
  // 2017's records, as guided-pt's), or both.
  enum class RadianceRecords : uint8_t { Photons, CameraPaths, Both };
  RadianceRecords radiance_records = RadianceRecords::CameraPaths;
  // The converse for the importance field (which guides light subpaths): the camera vertices
  // (importons: the importance arriving at each, Vorba et al. 2014), the light subpaths
  // themselves (the importance each guided light vertex received along its sampled direction:
  // what its later vertices' connections to the lens found, unweighted), or both.
  enum class ImportanceRecords : uint8_t { Importons, LightPaths, Both };
  ImportanceRecords importance_records = ImportanceRecords::LightPaths;
  // guided-bpt / guided-vcm: the MIS weights use the guided mixtures' densities, forward and
  // reverse (Vorba et al. 2014), or the BSDFs' alone, as unguided bpt/vcm would (the default).
  // Either is a partition of unity (every technique's weight comes from the same densities), so
  // both are unbiased; the BSDF's need no guide lookups and no quadtree densities outside
  // sampling, and the defensive mixture (a > 0) keeps each contribution within a factor 1/a per
  // guided vertex of the unguided technique's. door-ajar 320x240, 2 threads: per sample the
  // mixture's weights are 1.01-1.05x better (48 spp, seeds 1 and 2), per second the
  // BSDF's 1.10-1.14x; at 60 s guided-vcm is 0.96- 0.98x vcm's relMSE with the BSDF's and 1.11x
  // with the mixture's (seed 0).
  bool guided_mis = false;
  // Rendering passes enter the image weighted by their inverse variance (Müller 2019); false:
  // every iteration with equal weight.
  bool inverse_variance = true;
  // guided-pt: the probability of next event estimation at a vertex whose spatial leaf saw no
  // light in the last training pass that tested it (at least GuidingField::kNeeEvidence light
  // samples, none unoccluded with f > 0); everywhere else, and until then, 1. The light
  // sample's density is scaled by the probability in every weight, so the estimate stays
  // unbiased (guided_path_tracer.cpp). 1: next event estimation everywhere, as Müller et al.
  // guided-bpt / guided-vcm learn the same per leaf for next event estimation, lens
  // connections and connections, in their MIS sums (bidir/technique_probabilities.h); 1 there:
  // every technique at every vertex, as bpt / vcm.
  float nee_floor = 0.25f;
  // The share of a leaf's light samples that may see light for it still to count as seeing
  // none (0: not one). Above 0 the floor also reaches leaves where light arrives; the tests use
  // 1 (every leaf with enough samples) to check that the weights stay a partition of unity.
  float nee_visible_share = 0;
  // guided-bpt / guided-vcm: the same for connections of light vertices to camera vertices
  // (the larger of the two applies to them). Light that reaches a dark room through a gap is
  // seen by a few connections from everywhere along the sight lines through it: on door-ajar
  // (320x240, 64 spp) every radiance leaf in the lit room saw 1-5% of its connections
  // unoccluded, so with a share of 0 no leaf was reduced. With 5%, 35% fewer rays and 5% less
  // time at the same relMSE (three seeds); 10% gave 6.5% less time and a 6% higher relMSE.
  float connection_visible_share = 0.05f;
};

}  // namespace caustica
