// The options block (before WorldBegin): Camera, Film, Sampler, Integrator, PixelFilter,
// Accelerator; and ColorSpace, Option, WorldBegin and WorldEnd.
#include "io/pbrt/scene_converter.h"
#include "io/pbrt/transforms.h"

namespace caustica::pbrt {

namespace {

// The caustica integrator closest to a pbrt-v4 integrator.
std::string integrator_name(const std::string& pbrt_name, const SourceLocation& where,
                            LoaderContext& ctx) {
  if (pbrt_name == "path" || pbrt_name == "volpath" || pbrt_name == "simplepath" ||
      pbrt_name == "simplevolpath" || pbrt_name == "randomwalk")
    return "pt";
  if (pbrt_name == "bdpt") return "bpt";
  if (pbrt_name == "lightpath") return "lt";
  if (pbrt_name == "sppm") return "ppm";
  if (pbrt_name == "mlt") {
    ctx.warnings.warn(where, "integrator \"mlt\" is not available; using \"bpt\"");
    return "bpt";
  }
  if (pbrt_name == "ambientocclusion" || pbrt_name == "aov") {
    ctx.warnings.warn(where,
                      "integrator " + quote_excerpt(pbrt_name) + " is not available; using \"pt\"");
    return "pt";
  }
  throw SceneLoadError(where, "unknown integrator " + quote_excerpt(pbrt_name));
}

}  // namespace

void SceneConverter::camera(const Directive& d) {
  if (!is_invertible(state_.ctm))
    throw SceneLoadError(d.where, "Camera: the current transformation is singular");
  camera_from_world_ = state_.ctm;
  camera_media_ = state_.media;  // pbrt-v4: the camera is in the current outside medium
  coordinate_systems_["camera"] = state_.ctm.inverse();
  if (d.args[0] != "perspective") {
    ctx_.warnings.warn(
        d.where, "camera " + quote_excerpt(d.args[0]) + " is not supported; using \"perspective\"");
    d.params.mark_all_used();
  }
  camera_.fov_degrees = d.params.get_float("fov", 90);
  if (!(camera_.fov_degrees > 0 && camera_.fov_degrees < 180))
    param_error(*d.params.find("fov"), "expected an angle between 0 and 180 degrees");
  camera_.lens_radius = d.params.get_float("lensradius", 0);
  camera_.focal_distance = d.params.get_float("focaldistance", 1e6f);
  if (camera_.lens_radius < 0) param_error(*d.params.find("lensradius"), "must not be negative");
  if (!(camera_.focal_distance > 0))
    param_error(*d.params.find("focaldistance"), "must be positive");
  if (const Param* sw = d.params.find("screenwindow", {ParamType::Float})) {
    if (sw->numbers.size() != 4)
      param_error(*sw, "expected 4 values (xmin xmax ymin ymax), got " +
                           std::to_string(sw->numbers.size()));
    for (int i = 0; i < 4; ++i) camera_.screen_window[i] = float(sw->numbers[i]);
    if (!(camera_.screen_window[0] < camera_.screen_window[1] &&
          camera_.screen_window[2] < camera_.screen_window[3]))
      param_error(*sw, "expected xmin < xmax and ymin < ymax");
  }
  d.params.report_unused(ctx_.warnings, "Camera " + quote_excerpt(d.args[0]));
}

void SceneConverter::film(const Directive& d) {
  if (d.args[0] != "rgb" && d.args[0] != "gbuffer" && d.args[0] != "spectral")
    throw SceneLoadError(d.arg_where[0], "unknown film " + quote_excerpt(d.args[0]) +
                                             " (expected rgb, gbuffer or spectral)");
  camera_.width = d.params.get_int("xresolution", 1280);
  camera_.height = d.params.get_int("yresolution", 720);
  for (const char* r : {"xresolution", "yresolution"})
    if (const Param* p = d.params.find(r))
      if (!(p->numbers[0] >= 1 && p->numbers[0] <= 65536))
        param_error(*p, "expected a resolution between 1 and 65536");
  if (d.params.find("filename"))
    builder_.settings().output_name = d.params.get_string("filename", "");
  d.params.report_unused(ctx_.warnings, "Film " + quote_excerpt(d.args[0]));
}

void SceneConverter::sampler(const Directive& d) {
  const int spp = d.params.get_int("pixelsamples", 16);
  if (spp < 1) param_error(*d.params.find("pixelsamples"), "must be at least 1");
  builder_.settings().spp = spp;
  d.params.mark_all_used();  // sampler-specific settings (seed, randomization) do not apply
}

void SceneConverter::integrator(const Directive& d) {
  builder_.settings().integrator = integrator_name(d.args[0], d.arg_where[0], ctx_);
  const int depth = d.params.get_int("maxdepth", 5);
  if (depth < 0) param_error(*d.params.find("maxdepth"), "must not be negative");
  builder_.settings().max_depth = depth;
  d.params.report_unused(ctx_.warnings, "Integrator " + quote_excerpt(d.args[0]));
}

void SceneConverter::pixel_filter(const Directive& d) {
  const auto kind = pixel_filter_kind(d.args[0]);
  if (!kind)
    throw SceneLoadError(d.arg_where[0], "unknown pixel filter " + quote_excerpt(d.args[0]) +
                                             " (expected " + kPixelFilterNames + ")");
  PixelFilterParams& f = camera_.filter = PixelFilterParams::defaults(*kind);
  f.radius = {d.params.get_float("xradius", f.radius.x), d.params.get_float("yradius", f.radius.y)};
  for (const char* r : {"xradius", "yradius"})
    if (const Param* p = d.params.find(r))
      if (!(p->numbers[0] > 0 && p->numbers[0] <= 64))
        param_error(*p, "expected a radius greater than 0 and at most 64 pixels");
  if (*kind == PixelFilterKind::Gaussian) {
    f.sigma = d.params.get_float("sigma", f.sigma);
    if (!(f.sigma > 0)) param_error(*d.params.find("sigma"), "must be positive");
  } else if (*kind == PixelFilterKind::Mitchell) {
    f.b = d.params.get_float("B", f.b);
    f.c = d.params.get_float("C", f.c);
  } else if (*kind == PixelFilterKind::Lanczos) {
    f.tau = d.params.get_float("tau", f.tau);
    if (!(f.tau > 0)) param_error(*d.params.find("tau"), "must be positive");
  }
  d.params.report_unused(ctx_.warnings, "PixelFilter \"" + d.args[0] + "\"");
}

void SceneConverter::accelerator(const Directive& d) {
  d.params.mark_all_used();  // Embree builds its own BVH
}

void SceneConverter::color_space(const Directive& d) {
  if (d.args[0] != "srgb")
    ctx_.warnings.warn(d.where,
                       "ColorSpace " + quote_excerpt(d.args[0]) + " is not supported; using srgb",
                       "colorspace");
}

void SceneConverter::option(const Directive& d) {
  const Param& p = d.params.all()[0];
  ctx_.warnings.warn(p.where, "Option " + p.declaration() + " is not supported; ignored",
                     "option " + p.name);
}

void SceneConverter::world_begin(const Directive& d) {
  if (world_) throw SceneLoadError(d.where, "WorldBegin appears twice");
  world_ = true;
  state_.ctm = Transform();
  transforms_active_ = true;
  coordinate_systems_["world"] = Transform();
}

void SceneConverter::world_end(const Directive& d) {
  ctx_.warnings.warn(d.where, "WorldEnd is a pbrt-v3 directive; ignored");
}

}  // namespace caustica::pbrt
