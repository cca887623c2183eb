// pbrt-v4 textures and materials from their parameter lists.
//
// Textures (`Texture "name" "float"|"spectrum" "class"`): imagemap (filename relative to the
// scene file; encoding sRGB by default only for .png, else linear; uscale, vscale, udelta,
// vdelta, scale, invert), checkerboard (2D), scale, constant, mix. Others warn and become
// a constant.
//
// Materials: diffuse, conductor (eta/k or reflectance; roughness, uroughness, vroughness,
// remaproughness), dielectric (eta as float or named spectrum), thindielectric,
// coateddiffuse, coatedconductor, diffusetransmission, mix, and interface (no surface: a null
// material). measured, hair and subsurface warn and fall back to diffuse.
#pragma once

#include <functional>
#include <map>
#include <optional>
#include <string>

#include "geometry/texture.h"
#include "image/image.h"
#include "io/pbrt/context.h"
#include "io/pbrt/parameters.h"
#include "io/pbrt/spectrum_param.h"
#include "materials/material.h"

namespace caustica::pbrt {

class MaterialFactory {
 public:
  explicit MaterialFactory(LoaderContext& ctx) : ctx_(ctx) {}

  // The Texture directive: `type` is "float" or "spectrum".
  void define_texture(const std::string& name, const std::string& type, const std::string& cls,
                      const ParamList& params, const SourceLocation& where,
                      const SourceLocation& name_where);

  // Looks up named materials for "mix" (and detects cycles in the caller).
  using NamedMaterialLookup =
      std::function<MaterialPtr(const std::string& name, const SourceLocation& where)>;
  // Returns null for "interface" (and "" / "none"): a boundary that does not scatter.
  MaterialPtr make_material(const std::string& type, const ParamList& params,
                            const SourceLocation& where, const NamedMaterialLookup& named);

  // A colour parameter (rgb, spectrum, blackbody or a spectrum texture); null if absent and
  // there is no default.
  TexturePtr spectrum_texture(const ParamList& params, const std::string& name,
                              std::optional<Rgb> def, SpectrumKind kind);
  // A scalar parameter (float or a float texture); null if absent and no default.
  TexturePtr float_texture(const ParamList& params, const std::string& name,
                           std::optional<float> def);

  std::shared_ptr<const Image> load_image(const std::string& path, bool srgb, const Param& where);

 private:
  void roughness(const ParamList& params, const std::string& prefix, TexturePtr* u, TexturePtr* v,
                 bool* remap);
  float eta(const ParamList& params, const std::string& name);
  float thickness(const ParamList& params);
  void conductor_ior(const ParamList& params, const std::string& prefix, const std::string& type,
                     const SourceLocation& where, TexturePtr* eta, TexturePtr* k,
                     TexturePtr* reflectance);
  MaterialPtr conductor(const ParamList& params, const SourceLocation& where);
  MaterialPtr coated_conductor(const ParamList& params, const SourceLocation& where);
  MaterialPtr coated_diffuse(const ParamList& params, const SourceLocation& where);
  MaterialPtr mix(const ParamList& params, const SourceLocation& where,
                  const NamedMaterialLookup& named);
  TexturePtr texture_param(const ParamList& params, const std::string& name, bool is_float,
                           Rgb def);

  LoaderContext& ctx_;
  std::map<std::string, TexturePtr> float_textures_, spectrum_textures_;
  std::map<std::pair<std::string, bool>, std::shared_ptr<const Image>> images_;
};

}  // namespace caustica::pbrt
