// tinygltf is compiled once, in tinygltf_impl.cpp; this file sees only its declarations.
#define TINYGLTF_NO_STB_IMAGE_WRITE
#define TINYGLTF_NO_INCLUDE_STB_IMAGE_WRITE
#include "image/image.h"
#include "io/gltf/gltf_converter.h"
#include "io/gltf/gltf_input.h"
#include "lights/light_power.h"
#include "materials/materials.h"

namespace caustica::gltf_input {

TexturePtr GltfConverter::base_color_texture(const tinygltf::Material& m,
                                             const std::string& where) {
  const auto& pbr = m.pbrMetallicRoughness;
  Rgb factor(1.f);
  if (pbr.baseColorFactor.size() >= 3)
    factor = Rgb(float(pbr.baseColorFactor[0]), float(pbr.baseColorFactor[1]),
                 float(pbr.baseColorFactor[2]));
  factor = clamp(factor, 0.f, 1.f);
  const int tex = pbr.baseColorTexture.index;
  if (tex < 0) return make_constant_texture(factor);
  if (size_t(tex) >= model_.textures.size())
    fail(where + ".pbrMetallicRoughness.baseColorTexture: texture " + std::to_string(tex) +
         " does not exist (" + std::to_string(model_.textures.size()) + " textures)");
  if (pbr.baseColorTexture.texCoord != 0)
    warn("texture coordinate sets other than TEXCOORD_0 are not supported");
  if (!pbr.baseColorTexture.extensions.empty())
    warn("texture extensions (KHR_texture_transform) are not supported; ignored");
  const int source = model_.textures[size_t(tex)].source;
  if (source < 0 || size_t(source) >= model_.images.size()) {
    warn("texture without a supported image source; using the base colour factor");
    return make_constant_texture(factor);
  }
  auto it = images_.find(source);
  if (it == images_.end()) {
    const tinygltf::Image& src = model_.images[size_t(source)];
    const std::string name = index_path("images", size_t(source));
    if (src.width <= 0 || src.height <= 0 || src.image.empty() ||
        (src.bits != 8 && src.bits != 16) || src.component < 1)
      fail(name + " (" + quote_excerpt(src.uri, kPathExcerpt) + ") could not be decoded");
    const size_t bytes = size_t(src.bits / 8), comps = size_t(src.component);
    if (src.image.size() / bytes / comps / size_t(src.width) < size_t(src.height))
      fail(name + " is truncated");
    auto image = std::make_shared<Image>(src.width, src.height);
    for (int y = 0; y < src.height; ++y)
      for (int x = 0; x < src.width; ++x) {
        const size_t base = (size_t(y) * size_t(src.width) + size_t(x)) * comps;
        Rgb c;
        for (size_t k = 0; k < 3; ++k) {
          const size_t ch = std::min(k, comps > 2 ? k : size_t(0));
          float v;
          if (bytes == 1) {
            v = src.image[base + ch] / 255.f;
          } else {
            uint16_t u;
            std::memcpy(&u, &src.image[(base + ch) * 2], 2);
            v = u / 65535.f;
          }
          c[int(k)] = srgb_to_linear(v);  // base colour textures are sRGB-encoded
        }
        image->at(x, y) = c;
      }
    it = images_.emplace(source, image).first;
  }
  // glTF's uv origin is the top-left of the image; ImageTexture's v = 0 is the bottom row.
  UvMapping flip;
  flip.sv = -1;
  flip.dv = 1;
  return std::make_shared<ImageTexture>(it->second, flip, factor);
}

MaterialPtr GltfConverter::material(int index) {
  auto found = materials_.find(index);
  if (found != materials_.end()) return found->second;
  MaterialPtr result;
  std::optional<AreaEmission> emission;
  if (index < 0) {
    result =
        make_diffuse(make_constant_texture(Rgb(0.8f)));  // glTF's default material is white-ish
  } else {
    if (size_t(index) >= model_.materials.size())
      fail("material " + std::to_string(index) + " does not exist (" +
           std::to_string(model_.materials.size()) + " materials)");
    const std::string where = index_path("materials", size_t(index));
    const tinygltf::Material& m = model_.materials[size_t(index)];
    const auto& pbr = m.pbrMetallicRoughness;
    const float metallic = clamp(float(pbr.metallicFactor), 0.f, 1.f);
    const float roughness = clamp(float(pbr.roughnessFactor), 0.f, 1.f);
    // glTF roughness is perceptual: GGX alpha = roughness^2.
    TexturePtr alpha = roughness > 0 ? make_constant_texture(Rgb(roughness * roughness)) : nullptr;
    TexturePtr base = base_color_texture(m, where);
    if (pbr.metallicRoughnessTexture.index >= 0)
      warn("metallicRoughnessTexture is not supported; using the factors");
    if (m.normalTexture.index >= 0) warn("normal textures are not supported; ignored");
    if (m.occlusionTexture.index >= 0) warn("occlusion textures are not supported; ignored");
    if (m.emissiveTexture.index >= 0)
      warn("emissive textures are not supported; using emissiveFactor");
    if (m.alphaMode != "OPAQUE")
      warn("alphaMode " + quote_excerpt(m.alphaMode) + " is not supported; surfaces are opaque");

    double ior = 1.5, transmission = 0, strength = 1;
    if (const tinygltf::Value* v = extension(m.extensions, "KHR_materials_ior"))
      if (v->Has("ior")) ior = v->Get("ior").GetNumberAsDouble();
    if (const tinygltf::Value* v = extension(m.extensions, "KHR_materials_transmission"))
      if (v->Has("transmissionFactor"))
        transmission = v->Get("transmissionFactor").GetNumberAsDouble();
    if (const tinygltf::Value* v = extension(m.extensions, "KHR_materials_emissive_strength"))
      if (v->Has("emissiveStrength")) strength = v->Get("emissiveStrength").GetNumberAsDouble();
    if (!in_range(ior, 0, HUGE_VAL))
      fail(where + ": KHR_materials_ior.ior: expected a finite number >= 1 (or 0), got " +
           format_number(ior));
    if (!in_range(transmission, 0, 1))
      fail(where +
           ": KHR_materials_transmission.transmissionFactor: expected a number in "
           "[0, 1], got " +
           format_number(transmission));
    if (!in_range(strength, 0, HUGE_VAL))
      fail(where +
           ": KHR_materials_emissive_strength.emissiveStrength: expected a finite "
           "number >= 0, got " +
           format_number(strength));
    for (const auto& [name, value] : m.extensions)
      if (name != "KHR_materials_ior" && name != "KHR_materials_transmission" &&
          name != "KHR_materials_emissive_strength")
        warn("material extension " + quote_excerpt(name) + " is not supported; ignored");
    if (!(ior >= 1)) ior = 1.5;  // ior 0 means "no refraction" in glTF; 1.5 is its default

    if (transmission > 0) {
      DielectricParams d;
      d.eta = float(ior);
      d.u_roughness = d.v_roughness = alpha;
      d.remap_roughness = false;
      result = make_dielectric(d);
    } else {
      MaterialPtr metal, plastic;
      if (metallic > 0) {
        ConductorParams c;
        c.reflectance = base;
        c.u_roughness = c.v_roughness = alpha;
        c.remap_roughness = false;
        metal = make_conductor(c);
      }
      if (metallic < 1) {
        CoatedDiffuseParams c;
        c.reflectance = base;
        c.u_roughness = c.v_roughness = alpha ? alpha : make_constant_texture(Rgb(0.f));
        c.remap_roughness = false;
        c.eta = float(ior);
        plastic = make_coated_diffuse(c);
      }
      result = !metal     ? plastic
               : !plastic ? metal
                          : make_mix(plastic, metal, make_constant_texture(Rgb(metallic)));
    }
    if (m.emissiveFactor.size() == 3) {
      for (double e : m.emissiveFactor)
        if (!in_range(e, 0, HUGE_VAL))
          fail(where + ".emissiveFactor: expected finite numbers >= 0, got " + format_number(e));
      const Rgb e =
          Rgb(float(m.emissiveFactor[0]), float(m.emissiveFactor[1]), float(m.emissiveFactor[2])) *
          float(strength);
      if (!e.is_finite())
        fail(where + ": emissiveFactor times emissiveStrength overflows to infinity");
      if (!e.is_black()) emission = AreaEmission{e, m.doubleSided};
    }
  }
  materials_[index] = result;
  emission_[index] = emission;
  return result;
}

}  // namespace caustica::gltf_input
