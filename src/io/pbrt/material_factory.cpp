#include "io/pbrt/material_factory.h"

#include <algorithm>
#include <filesystem>
#include <limits>
#include <stdexcept>

#include "image/image_io.h"
#include "materials/materials.h"

namespace caustica::pbrt {

namespace {

// pbrt-v4 "mix" texture: lerp(amount, tex1, tex2).
class MixTexture final : public Texture {
 public:
  MixTexture(TexturePtr a, TexturePtr b, TexturePtr amount)
      : a_(std::move(a)), b_(std::move(b)), amount_(std::move(amount)) {}
  Rgb eval(const TextureContext& ctx) const override {
    const float t = amount_->eval_float(ctx);
    return a_->eval(ctx) * (1 - t) + b_->eval(ctx) * t;
  }

 private:
  TexturePtr a_, b_, amount_;
};

// A constant float parameter must lie in [lo, hi]. Textured values are image data, read at
// render time, and are not checked here.
void check_constant_range(const ParamList& params, const std::string& name, float lo, float hi,
                          const char* expected) {
  for (const Param& p : params.all())  // not find(): that would mark the parameter used
    if (p.name == name && p.type == ParamType::Float)
      for (double v : p.numbers)
        if (!(v >= lo && v <= hi))
          param_error(p, std::string("expected ") + expected + ", got " + format_number(v));
}

bool is_constant_value(const TexturePtr& t, float v) {
  const auto* c = dynamic_cast<const ConstantTexture*>(t.get());
  return c && c->value() == Rgb(v);
}

std::string lower_extension(const std::string& path) {
  const size_t dot = path.find_last_of('.');
  if (dot == std::string::npos || path.find_first_of("/\\", dot) != std::string::npos) return {};
  std::string ext = path.substr(dot);
  std::transform(ext.begin(), ext.end(), ext.begin(),
                 [](unsigned char c) { return char(std::tolower(c)); });
  return ext;
}

}  // namespace

std::shared_ptr<const Image> MaterialFactory::load_image(const std::string& path, bool srgb,
                                                         const Param& where) {
  auto key = std::make_pair(path, srgb);
  auto it = images_.find(key);
  if (it != images_.end()) return it->second;
  std::shared_ptr<const Image> image;
  std::error_code ec;
  // On Linux a directory opens as a stream and would be reported as a corrupt image.
  if (std::filesystem::is_directory(path, ec))
    param_error(where, quote_excerpt(path, kPathExcerpt) + " is a directory");
  try {
    image = std::make_shared<const Image>(read_image(path, srgb));
  } catch (const std::exception& e) {
    param_error(where, e.what());
  }
  if (image->empty()) param_error(where, quote_excerpt(path, kPathExcerpt) + " is an empty image");
  images_[key] = image;
  return image;
}

TexturePtr MaterialFactory::texture_param(const ParamList& params, const std::string& name,
                                          bool is_float, Rgb def) {
  TexturePtr t = is_float ? float_texture(params, name, def.r)
                          : spectrum_texture(params, name, def, SpectrumKind::Albedo);
  return t;
}

TexturePtr MaterialFactory::spectrum_texture(const ParamList& params, const std::string& name,
                                             std::optional<Rgb> def, SpectrumKind kind) {
  const Param* p = params.find(name, {ParamType::Rgb, ParamType::Spectrum, ParamType::Blackbody,
                                      ParamType::Texture, ParamType::Float});
  if (!p) return def ? make_constant_texture(*def) : nullptr;
  if (p->type == ParamType::Texture) {
    if (p->strings.size() != 1) param_error(*p, "expected one texture name");
    auto it = spectrum_textures_.find(p->strings[0]);
    if (it == spectrum_textures_.end())
      param_error(*p, "no spectrum texture named " + quote_excerpt(p->strings[0]));
    return it->second;
  }
  if (p->type == ParamType::Float) {
    // pbrt-v4 accepts a float as a constant spectrum.
    if (p->numbers.size() != 1) param_error(*p, "expected one value");
    return make_constant_texture(Rgb(float(p->numbers[0])));
  }
  return make_constant_texture(spectrum_param_rgb(*p, kind, ctx_));
}

TexturePtr MaterialFactory::float_texture(const ParamList& params, const std::string& name,
                                          std::optional<float> def) {
  const Param* p = params.find(name, {ParamType::Float, ParamType::Texture});
  if (!p) return def ? make_constant_texture(Rgb(*def)) : nullptr;
  if (p->type == ParamType::Texture) {
    if (p->strings.size() != 1) param_error(*p, "expected one texture name");
    auto it = float_textures_.find(p->strings[0]);
    if (it == float_textures_.end())
      param_error(*p, "no float texture named " + quote_excerpt(p->strings[0]));
    return it->second;
  }
  if (p->numbers.size() != 1)
    param_error(*p, "expected one value, got " + std::to_string(p->numbers.size()));
  return make_constant_texture(Rgb(float(p->numbers[0])));
}

void MaterialFactory::define_texture(const std::string& name, const std::string& type,
                                     const std::string& cls, const ParamList& params,
                                     const SourceLocation& where,
                                     const SourceLocation& name_where) {
  bool is_float;
  if (type == "float")
    is_float = true;
  else if (type == "spectrum" || type == "color" || type == "rgb")
    is_float = false;
  else
    throw SceneLoadError(where, "Texture " + quote_excerpt(name) + ": unknown texture type " +
                                    quote_excerpt(type) + " (expected \"float\" or \"spectrum\")");
  auto& table = is_float ? float_textures_ : spectrum_textures_;
  if (table.count(name))
    throw SceneLoadError(name_where, "texture " + quote_excerpt(name) + " is defined twice");

  const std::string context = "Texture " + quote_excerpt(cls);
  UvMapping mapping;
  auto read_mapping = [&]() {
    const std::string m = params.get_string("mapping", "uv");
    if (m != "uv")
      ctx_.warnings.warn(params.find("mapping")->where,
                         "texture mapping " + quote_excerpt(m) + " is not supported; using \"uv\"",
                         "mapping " + m);
    mapping.su = params.get_float("uscale", 1);
    mapping.sv = params.get_float("vscale", 1);
    mapping.du = params.get_float("udelta", 0);
    mapping.dv = params.get_float("vdelta", 0);
    for (const char* unused : {"v1", "v2"}) params.find(unused);  // planar mapping vectors
  };

  TexturePtr tex;
  if (cls == "constant") {
    tex = texture_param(params, "value", is_float, Rgb(1.f));
  } else if (cls == "scale") {
    TexturePtr t = texture_param(params, "tex", is_float, Rgb(1.f));
    TexturePtr s = float_texture(params, "scale", 1.f);
    tex = is_constant_value(s, 1.f) ? t : std::make_shared<ScaleTexture>(t, s);
  } else if (cls == "mix") {
    TexturePtr a = texture_param(params, "tex1", is_float, Rgb(0.f));
    TexturePtr b = texture_param(params, "tex2", is_float, Rgb(1.f));
    check_constant_range(params, "amount", 0, 1, "an amount between 0 and 1");
    tex = std::make_shared<MixTexture>(a, b, float_texture(params, "amount", 0.5f));
  } else if (cls == "checkerboard") {
    read_mapping();
    const int dim = params.get_int("dimension", 2);
    if (dim != 2 && dim != 3) param_error(*params.find("dimension"), "expected 2 or 3");
    if (dim == 3)
      ctx_.warnings.warn(where,
                         "3D checkerboard textures are not supported; using the 2D one on uv");
    TexturePtr a = texture_param(params, "tex1", is_float, Rgb(1.f));
    TexturePtr b = texture_param(params, "tex2", is_float, Rgb(0.f));
    tex = std::make_shared<CheckerboardTexture>(a, b, mapping);
  } else if (cls == "imagemap") {
    read_mapping();
    const Param* fp = params.find("filename", {ParamType::String});
    if (!fp) throw SceneLoadError(where, "imagemap: \"string filename\" is required");
    const std::string filename = params.get_string("filename", "");
    const std::string path = ctx_.resolve(filename, fp->where);
    // pbrt-v4: 8-bit PNGs default to sRGB, every other format to linear.
    const std::string ext = lower_extension(filename);
    std::string encoding = params.get_string("encoding", ext == ".png" ? "sRGB" : "linear");
    bool srgb = false;
    if (encoding == "sRGB")
      srgb = true;
    else if (encoding == "linear")
      srgb = false;
    else if (encoding.rfind("gamma ", 0) == 0) {
      ctx_.warnings.warn(
          params.find("encoding")->where,
          "imagemap encoding " + quote_excerpt(encoding) + " is approximated by sRGB");
      srgb = true;
    } else {
      param_error(
          *params.find("encoding"),
          "expected \"sRGB\", \"linear\" or \"gamma <value>\", got " + quote_excerpt(encoding));
    }
    const std::string filter = params.get_string("filter", "bilinear");
    if (filter != "bilinear" && filter != "point" && filter != "trilinear" && filter != "ewa" &&
        filter != "EWA")
      param_error(*params.find("filter"),
                  "expected point, bilinear, trilinear or ewa, got " + quote_excerpt(filter));
    if (filter != "bilinear")
      ctx_.warnings.warn(
          params.find("filter")->where,
          "imagemap filter " + quote_excerpt(filter) + " is not supported; using bilinear",
          "filter " + filter);
    const std::string wrap = params.get_string("wrap", "repeat");
    Image::Wrap wrap_mode = Image::Wrap::Repeat;
    if (wrap == "clamp") {
      wrap_mode = Image::Wrap::Clamp;
    } else if (wrap == "black") {
      wrap_mode = Image::Wrap::Black;
    } else if (wrap == "octahedralsphere") {
      ctx_.warnings.warn(params.find("wrap")->where,
                         "imagemap wrap \"octahedralsphere\" is not supported; using repeat",
                         "wrap " + wrap);
    } else if (wrap != "repeat") {
      param_error(*params.find("wrap"),
                  "expected repeat, clamp, black or octahedralsphere, got " + quote_excerpt(wrap));
    }
    params.find("maxanisotropy");
    const float scale = params.get_float("scale", 1);
    const bool invert = params.get_bool("invert", false);
    tex = std::make_shared<ImageTexture>(load_image(path, srgb, *fp), mapping, Rgb(scale), invert,
                                         is_float, wrap_mode);
  } else if (cls == "bilerp" || cls == "directionmix" || cls == "dots" || cls == "fbm" ||
             cls == "wrinkled" || cls == "windy" || cls == "marble" || cls == "ptex") {
    ctx_.warnings.warn(
        where, "texture class " + quote_excerpt(cls) + " is not supported; using a constant 0.5",
        "texture " + cls);
    params.mark_all_used();
    tex = make_constant_texture(Rgb(0.5f));
  } else {
    throw SceneLoadError(
        where, "Texture " + quote_excerpt(name) + ": unknown texture class " + quote_excerpt(cls));
  }
  params.report_unused(ctx_.warnings, context);
  table[name] = std::move(tex);
}

// Roughness from "uroughness" and "vroughness", each defaulting to "roughness" (names after
// `prefix`), and "remaproughness"; both null for a constant zero: the smooth (delta) case.
void MaterialFactory::roughness(const ParamList& params, const std::string& prefix, TexturePtr* u,
                                TexturePtr* v, bool* remap) {
  *u = float_texture(params, prefix + "uroughness", std::nullopt);
  *v = float_texture(params, prefix + "vroughness", std::nullopt);
  TexturePtr r = float_texture(params, prefix + "roughness", 0.f);
  if (!*u) *u = r;
  if (!*v) *v = r;
  if (is_constant_value(*u, 0.f) && is_constant_value(*v, 0.f)) *u = *v = nullptr;
  *remap = params.get_bool("remaproughness", true);
}

// An index of refraction ("eta", "interface.eta") as one positive value, 1.5 if absent.
float MaterialFactory::eta(const ParamList& params, const std::string& name) {
  const Param* p = params.find(
      name, {ParamType::Float, ParamType::Spectrum, ParamType::Rgb, ParamType::Texture});
  float value = 1.5f;
  if (p && p->type == ParamType::Float) {
    if (p->numbers.size() != 1) param_error(*p, "expected one value");
    value = float(p->numbers[0]);
  } else if (p && p->type == ParamType::Texture) {
    ctx_.warnings.warn(p->where, "textured eta is not supported; using 1.5", "textured eta");
  } else if (p) {
    // Spectrally varying IORs (dispersion) are reduced to one value.
    value = spectrum_param_rgb(*p, SpectrumKind::Unbounded, ctx_).g;
  }
  if (!(value > 0)) param_error(*params.find(name), name + " must be positive");
  return value;
}

MaterialPtr MaterialFactory::make_material(const std::string& type, const ParamList& params,
                                           const SourceLocation& where,
                                           const NamedMaterialLookup& named) {
  // Bump mapping wraps whatever the type makes (materials/bump_mapped.cpp).
  const TexturePtr displacement = float_texture(params, "displacement", std::nullopt);
  if (params.find("normalmap"))
    ctx_.warnings.warn(where, "normal maps are not supported; ignored", "normalmap");
  const float kInf = std::numeric_limits<float>::infinity();
  // Negative roughness has no meaning (and its remapped alpha, sqrt(roughness), is NaN).
  for (const char* name : {"roughness", "uroughness", "vroughness", "conductor.roughness",
                           "conductor.uroughness", "conductor.vroughness", "interface.roughness",
                           "interface.uroughness", "interface.vroughness"})
    check_constant_range(params, name, 0, kInf, "a roughness >= 0");

  MaterialPtr m;
  if (type == "interface" || type.empty() || type == "none") {
    m = nullptr;
  } else if (type == "diffuse") {
    m = make_diffuse(spectrum_texture(params, "reflectance", Rgb(0.5f), SpectrumKind::Albedo));
  } else if (type == "conductor") {
    m = conductor(params, where);
  } else if (type == "coatedconductor") {
    m = coated_conductor(params, where);
  } else if (type == "dielectric") {
    DielectricParams d;
    d.eta = eta(params, "eta");
    roughness(params, "", &d.u_roughness, &d.v_roughness, &d.remap_roughness);
    m = make_dielectric(d);
  } else if (type == "thindielectric") {
    m = make_thin_dielectric(eta(params, "eta"));
  } else if (type == "coateddiffuse") {
    m = coated_diffuse(params, where);
  } else if (type == "diffusetransmission") {
    m = make_diffuse_transmission(
        spectrum_texture(params, "reflectance", Rgb(0.25f), SpectrumKind::Albedo),
        spectrum_texture(params, "transmittance", Rgb(0.25f), SpectrumKind::Albedo),
        params.get_float("scale", 1));
  } else if (type == "mix") {
    m = mix(params, where, named);
  } else if (type == "measured" || type == "hair" || type == "subsurface") {
    ctx_.warnings.warn(where,
                       "material " + quote_excerpt(type) + " is not supported; using diffuse",
                       "material " + type);
    TexturePtr r;
    if (type == "subsurface")
      r = spectrum_texture(params, "reflectance", std::nullopt, SpectrumKind::Albedo);
    params.mark_all_used();
    m = make_diffuse(r ? r : make_constant_texture(Rgb(0.5f)));
  } else {
    throw SceneLoadError(where, "unknown material type " + quote_excerpt(type));
  }
  params.report_unused(ctx_.warnings, "Material " + quote_excerpt(type));
  return make_bump_mapped(std::move(m), displacement);
}

// The conductor's complex IOR or reflectance (names after `prefix` for eta and k: "conductor."
// for coatedconductor), with pbrt-v4's copper default.
void MaterialFactory::conductor_ior(const ParamList& params, const std::string& prefix,
                                    const std::string& type, const SourceLocation& where,
                                    TexturePtr* eta, TexturePtr* k, TexturePtr* reflectance) {
  *reflectance = spectrum_texture(params, "reflectance", std::nullopt, SpectrumKind::Albedo);
  *eta = spectrum_texture(params, prefix + "eta", std::nullopt, SpectrumKind::Unbounded);
  *k = spectrum_texture(params, prefix + "k", std::nullopt, SpectrumKind::Unbounded);
  if (*reflectance && (*eta || *k))
    throw SceneLoadError(where, type + ": \"reflectance\" cannot be combined with \"" + prefix +
                                    "eta\" or \"" + prefix + "k\"");
  if (!*reflectance) {
    if (!*eta)
      *eta = make_constant_texture(named_spectrum("metal-Cu-eta").value_or(Rgb(0.2f, 0.92f, 1.1f)));
    if (!*k)
      *k = make_constant_texture(named_spectrum("metal-Cu-k").value_or(Rgb(3.9f, 2.45f, 2.14f)));
  }
}

MaterialPtr MaterialFactory::conductor(const ParamList& params, const SourceLocation& where) {
  ConductorParams c;
  conductor_ior(params, "", "conductor", where, &c.eta, &c.k, &c.reflectance);
  roughness(params, "", &c.u_roughness, &c.v_roughness, &c.remap_roughness);
  if (!c.u_roughness && c.reflectance && is_constant_value(c.reflectance, 1.f))
    return make_mirror(Rgb(1.f));  // pbrt-v4's conductor with reflectance 1 is a perfect mirror
  return make_conductor(c);
}

MaterialPtr MaterialFactory::coated_conductor(const ParamList& params,
                                              const SourceLocation& where) {
  CoatedConductorParams c;
  roughness(params, "interface.", &c.interface_u_roughness, &c.interface_v_roughness,
            &c.remap_roughness);
  roughness(params, "conductor.", &c.conductor_u_roughness, &c.conductor_v_roughness,
            &c.remap_roughness);
  c.interface_eta = eta(params, "interface.eta");
  conductor_ior(params, "conductor.", "coatedconductor", where, &c.eta, &c.k, &c.reflectance);
  c.thickness = thickness(params);
  c.albedo = spectrum_texture(params, "albedo", Rgb(0.f), SpectrumKind::Albedo);
  c.g = float_texture(params, "g", 0.f);
  c.max_depth = params.get_int("maxdepth", 10);
  c.n_samples = params.get_int("nsamples", 1);
  if (c.max_depth < 1 || c.n_samples < 1 || c.max_depth > 1000 || c.n_samples > 1000)
    throw SceneLoadError(where,
                         "coatedconductor: maxdepth and nsamples must be between 1 and 1000");
  return make_coated_conductor(c);
}

// "thickness" of a coat: a positive float (0.01 if absent); textured thickness is warned.
float MaterialFactory::thickness(const ParamList& params) {
  const Param* tp = params.find("thickness", {ParamType::Float, ParamType::Texture});
  if (tp && tp->type == ParamType::Texture) {
    ctx_.warnings.warn(tp->where, "textured coating thickness is not supported; using 0.01",
                       "textured thickness");
    return 0.01f;
  }
  return params.get_float("thickness", 0.01f);
}

MaterialPtr MaterialFactory::coated_diffuse(const ParamList& params, const SourceLocation& where) {
  CoatedDiffuseParams c;
  c.reflectance = spectrum_texture(params, "reflectance", Rgb(0.5f), SpectrumKind::Albedo);
  roughness(params, "", &c.u_roughness, &c.v_roughness, &c.remap_roughness);
  if (!c.u_roughness) c.u_roughness = c.v_roughness = make_constant_texture(Rgb(0.f));
  c.thickness = thickness(params);
  c.eta = eta(params, "eta");
  c.albedo = spectrum_texture(params, "albedo", Rgb(0.f), SpectrumKind::Albedo);
  c.g = float_texture(params, "g", 0.f);
  c.max_depth = params.get_int("maxdepth", 10);
  c.n_samples = params.get_int("nsamples", 1);
  if (c.max_depth < 1 || c.n_samples < 1 || c.max_depth > 1000 || c.n_samples > 1000)
    throw SceneLoadError(where, "coateddiffuse: maxdepth and nsamples must be between 1 and 1000");
  return make_coated_diffuse(c);
}

MaterialPtr MaterialFactory::mix(const ParamList& params, const SourceLocation& where,
                                 const NamedMaterialLookup& named) {
  const Param* mp = params.find("materials", {ParamType::String});
  if (!mp || mp->strings.size() != 2)
    throw SceneLoadError(mp ? mp->where : where,
                         "mix: \"string materials\" must name exactly two materials");
  MaterialPtr a = named(mp->strings[0], mp->where), b = named(mp->strings[1], mp->where);
  // The amount is the probability of choosing the second material.
  check_constant_range(params, "amount", 0, 1, "an amount between 0 and 1");
  TexturePtr amount = float_texture(params, "amount", 0.5f);
  if (!a && !b) return nullptr;
  if (!a || !b) {
    ctx_.warnings.warn(where,
                       "mix with an interface material is not supported; using the other material");
    return a ? a : b;
  }
  return make_mix(a, b, amount);
}

}  // namespace caustica::pbrt
