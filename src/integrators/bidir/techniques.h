// The MIS terms of every way the bidirectional core completes a path, computed from the
// vertices' hit records and BSDFs: the one place where geometry becomes the pdfs that MisRules
// combines. The weight is terms.weight(rules.counts()); adaptive-vcm also evaluates the same
// terms under other counts. The renderer and the tests' path replay (path_weights.h) both call
// these, so the partition-of-unity test exercises exactly the code that renders. The guides of a
// vertex (vertex_guides.h; guided-bpt and guided-vcm) make its densities the guided mixtures';
// left empty, they are the BSDF's.
#pragma once

#include "core/vec.h"
#include "geometry/interaction.h"
#include "integrators/bidir/mis.h"
#include "integrators/bidir/vertex_guides.h"
#include "materials/bsdf.h"

namespace caustica {
class Camera;
class Light;
struct LightLeSample;
struct LightLiSample;
}  // namespace caustica

namespace caustica::bidir {

// |cos| with the geometric normal: the measure conversions of the MIS pdfs (see mis.h).
inline float geometric_cos(const SurfaceInteraction& si, Vec3 w) { return abs_dot(si.ng, w); }

// Per-pixel solid-angle density of a camera ray leaving lens point p_lens along dir (0 off the
// film). raster_density: the pixel filter's density of the ray's raster offset from the pixel
// centre, per unit raster area (render/pixel_filter.h; 1 for the box of radius 1/2).
float camera_pdf_w(const Camera& camera, Vec3 p_lens, Vec3 dir, float raster_density = 1.f);

// MIS sums at the first light vertex y1, reached at distance dist from the emission sample.
// track: the subpath's merges for correlation-aware MIS (started here, and the sums' corr),
// when the rules are correlated.
MisSums light_subpath_start(const MisRules& rules, const Light& light, float pmf,
                            const LightLeSample& le, const SurfaceInteraction& y1, float dist,
                            CorrelationTrack* track = nullptr);
// Scattering at si from wo into wi; pdf_fwd is the sample's pdf (ignored for specular bounces).
void scatter_update(const MisRules& rules, MisSums& mis, const SurfaceInteraction& si,
                    const Bsdf& bsdf, Vec3 wo, Vec3 wi, TransportMode mode, bool specular,
                    float pdf_fwd, const VertexGuides& guides = {});

// Camera subpath reaches an emitter: an area light at `hit` (seen from prev_p) or, with hit ==
// nullptr, an infinite light along dir (leaving prev_p). `camera` is the camera sums at the
// emitter (after hit() for area lights, before it for infinite ones).
// nee_probability: that of next event estimation at prev_p toward dir (MisRules::hit_light).
TechniqueTerms terms_emitter_hit(const MisRules& rules, const Light& light, float pmf, Vec3 prev_p,
                                 Vec3 dir, const SurfaceInteraction* hit, const MisSums& camera,
                                 float nee_probability = 1);
// The camera ray hits an area light straight from the lens (s = 0, t = 2): weighted against the
// light subpaths' emission points connected to the lens (s = 1, t = 1). `camera`: the sums at
// the light (after hit()).
TechniqueTerms terms_light_seen_from_lens(const MisRules& rules, const Light& light, float pmf,
                                          const SurfaceInteraction& hit, const MisSums& camera);
// Next event estimation from camera vertex (si, bsdf) with wo.
TechniqueTerms terms_next_event(const MisRules& rules, const Light& light, float pmf,
                                const LightLiSample& ls, const SurfaceInteraction& si,
                                const Bsdf& bsdf, const MisSums& camera,
                                const VertexGuides& guides = {});
// Connection of light vertex (light_si with its wo, BSDF, sums) and camera vertex.
TechniqueTerms terms_connection(const MisRules& rules, const SurfaceInteraction& light_si,
                                const Bsdf& light_bsdf, Vec3 light_wo, const MisSums& light,
                                const SurfaceInteraction& camera_si, const Bsdf& camera_bsdf,
                                const MisSums& camera, const VertexGuides& light_guides = {},
                                const VertexGuides& camera_guides = {});
// Light vertex connected to the lens point p_lens, splatted to a pixel whose camera technique
// has raster density raster_density there (camera_pdf_w). A splat reaches every pixel the filter
// covers (up to 16 for pbrt-v4's default Gaussian): what does not depend on the pixel is
// computed once (LensConnection), the terms per pixel from it.
struct LensConnection {
  float pixels_pdf_dir = 0;  // pixel_count x the camera's pdf_we direction density
  float cos_at_vertex = 0;   // |cos| at the light vertex, with its geometric normal
  float dist2 = 0;
  float rev = 0;  // the density of a camera subpath leaving the light vertex toward wo
};
LensConnection lens_connection(const Camera& camera, const SurfaceInteraction& si, const Bsdf& bsdf,
                               Vec3 wo, Vec3 p_lens, const VertexGuides& guides = {});
TechniqueTerms terms_light_to_camera(const MisRules& rules, const LensConnection& c,
                                     const MisSums& light, float raster_density = 1.f);
TechniqueTerms terms_light_to_camera(const MisRules& rules, const Camera& camera,
                                     const SurfaceInteraction& si, const Bsdf& bsdf, Vec3 wo,
                                     const MisSums& light, Vec3 p_lens, float raster_density = 1.f,
                                     const VertexGuides& guides = {});
// An area light's emission point p (geometric normal n) connected to the lens point p_lens
// (s = 1, t = 1); emission_pos_pdf = pmf * pdf_pos. The connection's rev is unused. Both
// lens_connection functions take p_lens from a sample_wi that reached the film (no film test).
LensConnection lens_connection_of_emission(const Camera& camera, Vec3 p, Vec3 n, Vec3 p_lens);
TechniqueTerms terms_light_origin_to_camera(const MisRules& rules, const LensConnection& c,
                                            float emission_pos_pdf, float raster_density = 1.f);
// Merge of a light vertex that arrived along light_wo with a camera vertex.
TechniqueTerms terms_merge(const MisRules& rules, Vec3 light_wo, const MisSums& light,
                           const SurfaceInteraction& camera_si, const Bsdf& camera_bsdf,
                           const MisSums& camera, const VertexGuides& camera_guides = {});

}  // namespace caustica::bidir
