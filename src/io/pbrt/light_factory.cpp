#include "io/pbrt/light_factory.h"

#include <cmath>

#include "lights/light_power.h"
#include "lights/lights.h"

namespace caustica::pbrt {

namespace {

// Emission is checked where it is computed: a value that overflowed to infinity would make
// the light's power, and so the light selection distribution, infinite or NaN at render time.
// `blame` is the parameter whose factor made it overflow.
Rgb check_emission(Rgb value, const Param& blame, const char* what) {
  if (!value.is_finite())
    param_error(blame, "makes the " + std::string(what) + " overflow to infinity");
  return value;
}

// "scale" of a light: a non-negative factor.
float light_scale(const ParamList& params) {
  const float scale = params.get_float("scale", 1);
  if (scale < 0) param_error(*params.find("scale"), "must not be negative");
  return scale;
}

// The emitted RGB of a light's spectrum parameter, default the illuminant (white), times
// "scale".
Rgb emission(const ParamList& params, const char* name, LoaderContext& ctx) {
  const Param* p = params.find(name, {ParamType::Rgb, ParamType::Spectrum, ParamType::Blackbody});
  const Rgb rgb = p ? spectrum_param_rgb(*p, SpectrumKind::Illuminant, ctx) : Rgb(1.f);
  if (p) check_emission(rgb, *p, "emission");
  const float scale = light_scale(params);
  const Param* sp = params.find("scale");
  return sp ? check_emission(rgb * scale, *sp, "emission") : rgb;
}

// A "power", "illuminance" or "scale" given as a multiplier of `value`.
Rgb scaled_by(const ParamList& params, const char* name, Rgb value, float factor) {
  return check_emission(value * factor, *params.find(name), "emission");
}

// Point and spot lights know their power at load time; it must be finite too (4 pi I can
// overflow where I does not).
void check_power(const Light& light, const SourceLocation& where) {
  if (!light.power().is_finite())
    throw SceneLoadError(where, "the light's total power overflows to infinity");
}

LightPtr point_light(const ParamList& params, const SourceLocation& where,
                     const Transform& light_to_world, LoaderContext& ctx) {
  Rgb I = emission(params, "I", ctx);
  const float power = params.get_float("power", -1);
  if (power > 0) I = scaled_by(params, "power", I, power / point_light_power_per_intensity());
  const Vec3 from = light_to_world.point(params.get_point3("from", {0, 0, 0}));
  if (!is_finite(from)) throw SceneLoadError(where, "point light position is not finite");
  LightPtr light = make_point_light(from, I);
  check_power(*light, where);
  return light;
}

LightPtr spot_light(const ParamList& params, const SourceLocation& where,
                    const Transform& light_to_world, LoaderContext& ctx) {
  Rgb I = emission(params, "I", ctx);
  const float cone = params.get_float("coneangle", 30),
              delta = params.get_float("conedeltaangle", 5);
  const Vec3 from = params.get_point3("from", {0, 0, 0}), to = params.get_point3("to", {0, 0, 1});
  if (from == to) throw SceneLoadError(where, "spot: \"from\" and \"to\" are the same point");
  const float power = params.get_float("power", -1);
  if (power > 0) {
    // The cone's cosines unclamped, as pbrt-v4 SpotLight::Create takes them. The light model
    // clamps a falloff band wider than the cone (make_spot_light), so such a light does not
    // emit exactly "power".
    const float cos_end = std::cos(radians(cone)), cos_start = std::cos(radians(cone - delta));
    const float k_e = spot_light_power_per_intensity(cos_start, cos_end);
    if (k_e > 0) I = scaled_by(params, "power", I, power / k_e);
  }
  const Vec3 p = light_to_world.point(from), dir = light_to_world.vector(to - from);
  if (!is_finite(p) || !(length(dir) > 0) || !is_finite(dir))
    throw SceneLoadError(where, "spot light transform is degenerate");
  LightPtr light = make_spot_light(p, normalize(dir), I, cone, delta);
  check_power(*light, where);
  return light;
}

LightPtr distant_light(const ParamList& params, const SourceLocation& where,
                       const Transform& light_to_world, LoaderContext& ctx) {
  Rgb L = emission(params, "L", ctx);
  const Vec3 from = params.get_point3("from", {0, 0, 0}), to = params.get_point3("to", {0, 0, 1});
  if (from == to) throw SceneLoadError(where, "distant: \"from\" and \"to\" are the same point");
  const float illuminance = params.get_float("illuminance", -1);
  if (illuminance > 0) L = scaled_by(params, "illuminance", L, illuminance);
  const Vec3 dir = light_to_world.vector(to - from);
  if (!(length(dir) > 0) || !is_finite(dir))
    throw SceneLoadError(where, "distant light transform is degenerate");
  return make_distant_light(normalize(dir), L);
}

// A uniform sky ("L") or an image ("filename").
LightPtr infinite_light(const ParamList& params, const SourceLocation& where,
                        const Transform& light_to_world, MaterialFactory& images,
                        LoaderContext& ctx) {
  const Param* lp = params.find("L");
  const Param* fp = params.find("filename", {ParamType::String});
  if (lp && fp)
    throw SceneLoadError(where, "infinite: \"L\" and \"filename\" cannot both be given");
  if (params.find("portal"))
    ctx.warnings.warn(params.find("portal")->where,
                      "infinite light portals are not supported; ignored", "portal");
  if (!fp) {
    Rgb L = emission(params, "L", ctx);
    const float illuminance = params.get_float("illuminance", -1);
    // A uniform sky of radiance 1 gives E = pi.
    if (illuminance > 0) L = scaled_by(params, "illuminance", L, illuminance / kPi);
    return make_uniform_environment(L);
  }
  const float scale = light_scale(params);
  if (params.find("illuminance"))
    ctx.warnings.warn(params.find("illuminance")->where,
                      "\"illuminance\" is not supported for image infinite lights; ignored",
                      "image illuminance");
  const std::string path = ctx.resolve(params.get_string("filename", ""), fp->where);
  std::shared_ptr<const Image> image = images.load_image(path, false, *fp);
  EnvironmentMapping mapping = EnvironmentMapping::EqualAreaOctahedral;
  if (image->width() != image->height()) {
    ctx.warnings.warn(fp->where, "environment map " + quote_excerpt(fp->strings[0]) + " is " +
                                     std::to_string(image->width()) + "x" +
                                     std::to_string(image->height()) +
                                     ", not square: reading it as lat-long (pbrt-v4 expects an "
                                     "equal-area octahedral map)");
    mapping = EnvironmentMapping::LatLong;
  }
  return make_image_environment(image, mapping, light_to_world, Rgb(scale));
}

}  // namespace

AreaLightDesc make_area_light(const std::string& type, const ParamList& params,
                              const SourceLocation& where, LoaderContext& ctx) {
  if (type != "diffuse")
    throw SceneLoadError(
        where, "unknown area light type " + quote_excerpt(type) + " (expected \"diffuse\")");
  AreaLightDesc a;
  a.where = where;
  if (const Param* fp = params.find("filename")) {
    ctx.warnings.warn(fp->where, "image-textured area lights are not supported; using \"L\"",
                      "area light filename");
  }
  a.radiance = emission(params, "L", ctx);
  a.two_sided = params.get_bool("twosided", false);
  a.power = params.get_float("power", -1);
  params.report_unused(ctx.warnings, "AreaLightSource \"diffuse\"");
  return a;
}

void add_light_source(const std::string& type, const ParamList& params, const SourceLocation& where,
                      const Transform& light_to_world, MaterialFactory& images,
                      SceneBuilder& builder, LoaderContext& ctx) {
  LightPtr light;
  if (type == "point") {
    light = point_light(params, where, light_to_world, ctx);
  } else if (type == "spot") {
    light = spot_light(params, where, light_to_world, ctx);
  } else if (type == "distant") {
    light = distant_light(params, where, light_to_world, ctx);
  } else if (type == "infinite") {
    light = infinite_light(params, where, light_to_world, images, ctx);
  } else if (type == "goniometric" || type == "projection") {
    ctx.warnings.warn(where, "light " + quote_excerpt(type) + " is not supported; skipped",
                      "light " + type);
    params.mark_all_used();
    return;
  } else {
    throw SceneLoadError(
        where, "unknown light type " + quote_excerpt(type) +
                   " (expected point, spot, distant, infinite, goniometric or projection)");
  }
  params.report_unused(ctx.warnings, "LightSource " + quote_excerpt(type));
  builder.add_light(std::move(light));
}

}  // namespace caustica::pbrt
