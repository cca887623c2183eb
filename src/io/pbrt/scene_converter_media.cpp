// pbrt-v4's participating media as far as caustica renders them: homogeneous media that absorb
// (geometry/medium.h). MakeNamedMedium defines one; MediumInterface sets the media inside and
// outside the shapes that follow (and, before Camera, the camera's).
#include <algorithm>
#include <cmath>

#include "io/pbrt/scene_converter.h"
#include "io/pbrt/spectrum_param.h"

namespace caustica::pbrt {

void SceneConverter::make_named_medium(const Directive& d) {
  const std::string& name = d.args[0];
  const SourceLocation& where = d.arg_where.empty() ? d.where : d.arg_where[0];
  if (media_.count(name))
    throw SceneLoadError(where, "medium " + quote_excerpt(name) + " is defined twice");
  const Param* tp = d.params.find("type", {ParamType::String});
  if (!tp) throw SceneLoadError(d.where, "MakeNamedMedium: \"string type\" is required");
  const std::string type = d.params.get_string("type", "");
  if (type != "homogeneous") {
    ctx_.warnings.warn(tp->where,
                       "medium type " + quote_excerpt(type) +
                           " is not supported (only \"homogeneous\"); the medium is left out",
                       "medium " + type);
    d.params.mark_all_used();
    media_[name] = std::nullopt;
    return;
  }
  const Param* sp = d.params.find("scale", {ParamType::Float});
  const float scale = d.params.get_float("scale", 1);
  if (sp && !(scale >= 0 && std::isfinite(scale))) param_error(*sp, "expected a finite value >= 0");
  // Absorption or scattering per unit length, times "scale": pbrt-v4's default is a constant 1.
  auto coefficient = [&](const char* param) {
    const Param* p = d.params.find(
        param, {ParamType::Rgb, ParamType::Spectrum, ParamType::Blackbody, ParamType::Float});
    Rgb value(1.f);
    if (p && p->type == ParamType::Float) {
      if (p->numbers.size() != 1) param_error(*p, "expected one value");
      value = Rgb(float(p->numbers[0]));
    } else if (p) {
      value = spectrum_param_rgb(*p, SpectrumKind::Unbounded, ctx_);
    }
    value = value * scale;
    if (!(value.is_finite() && std::min({value.r, value.g, value.b}) >= 0))
      param_error(p ? *p : *sp, "expected finite values >= 0 (times \"scale\")");
    return value;
  };
  const Rgb sigma_a = coefficient("sigma_a"), sigma_s = coefficient("sigma_s");
  if (sigma_s.max_component() > 0)
    ctx_.warnings.warn(d.where,
                       "scattering in media is not supported; medium " + quote_excerpt(name) +
                           " only absorbs (sigma_a)",
                       "medium scattering");
  if (const Param* p = d.params.find("preset"))
    ctx_.warnings.warn(p->where, "medium presets are not supported; using sigma_a and sigma_s",
                       "medium preset");
  for (const char* param : {"Le", "Lescale"})
    if (const Param* p = d.params.find(param))
      ctx_.warnings.warn(p->where, "emissive media are not supported; ignored", "medium Le");
  d.params.find("g");  // the phase function matters only where light scatters
  d.params.report_unused(ctx_.warnings, "MakeNamedMedium " + quote_excerpt(name));
  media_[name] = builder_.add_medium({sigma_a});
}

void SceneConverter::medium_interface(const Directive& d) {
  state_.media.inside = d.args[0];
  state_.media.outside = d.args.size() > 1 ? d.args[1] : d.args[0];
  state_.media.where = d.where;
}

int16_t SceneConverter::medium_index(const std::string& name, const SourceLocation& where) const {
  if (name.empty()) return kNoMedium;
  auto it = media_.find(name);
  if (it == media_.end())
    throw SceneLoadError(where, "MediumInterface: medium " + quote_excerpt(name) +
                                    " is not defined (no MakeNamedMedium of that name)");
  return it->second.value_or(kNoMedium);
}

MediumInterface SceneConverter::medium_interface_of(const MediumNames& names) const {
  return {medium_index(names.inside, names.where), medium_index(names.outside, names.where)};
}

}  // namespace caustica::pbrt
