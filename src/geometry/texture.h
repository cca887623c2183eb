// Textures: functions of the surface point that materials evaluate at each hit.
// All textures are RGB; scalar parameters (roughness) read the average channel.
#pragma once

#include <memory>

#include "core/rgb.h"
#include "core/vec.h"
#include "image/image.h"

namespace caustica {

struct TextureContext {
  Vec2 uv;
  Vec3 p;
};

class Texture {
 public:
  virtual ~Texture() = default;
  virtual Rgb eval(const TextureContext& ctx) const = 0;
  float eval_float(const TextureContext& ctx) const { return eval(ctx).average(); }
  // True if eval() returns the same value everywhere (lets materials skip work).
  virtual bool is_constant() const { return false; }
};

using TexturePtr = std::shared_ptr<const Texture>;

class ConstantTexture final : public Texture {
 public:
  explicit ConstantTexture(Rgb value) : value_(value) {}
  Rgb eval(const TextureContext&) const override { return value_; }
  bool is_constant() const override { return true; }
  Rgb value() const { return value_; }

 private:
  Rgb value_;
};

// How uv maps into a texture: (u * uscale + udelta, v * vscale + vdelta), as pbrt-v4's UVMapping.
struct UvMapping {
  float su = 1, sv = 1, du = 0, dv = 0;
  Vec2 map(Vec2 uv) const { return {uv.x * su + du, uv.y * sv + dv}; }
};

// Bilinearly filtered image lookup with repeat wrapping, as pbrt-v4's "imagemap" texture with
// filter "bilinear" and wrap "repeat" (no MIP mapping). pbrt convention: (s, t) = mapping(uv)
// and t = 0 is the bottom of the image (images are stored top row first), so the lookup is at
// (s, 1 - t); texel centres sit at half-integer multiples of 1/width, 1/height. The result is
// max(0, invert ? 1 - scale * texel : scale * texel), as pbrt-v4 computes it. A float texture
// (first_channel) reads the image's first channel, as pbrt-v4's float MIP maps do, not the mean.
class ImageTexture final : public Texture {
 public:
  // Throws std::invalid_argument if `image` is null or empty.
  // wrap: what texels outside the image read (pbrt-v4's wrap modes repeat, clamp and black).
  ImageTexture(std::shared_ptr<const Image> image, UvMapping mapping, Rgb scale = Rgb(1.f),
               bool invert = false, bool first_channel = false,
               Image::Wrap wrap = Image::Wrap::Repeat);
  Rgb eval(const TextureContext& ctx) const override;

 private:
  std::shared_ptr<const Image> image_;
  UvMapping mapping_;
  Rgb scale_;
  bool invert_;
  bool first_channel_;
  Image::Wrap wrap_;
};

// 2D checkerboard (pbrt-v4 "checkerboard", dimension 2, without its filtering): with
// (s, t) = mapping(uv), tex1 where floor(s) + floor(t) is even, tex2 otherwise.
class CheckerboardTexture final : public Texture {
 public:
  CheckerboardTexture(TexturePtr tex1, TexturePtr tex2, UvMapping mapping)
      : tex1_(std::move(tex1)), tex2_(std::move(tex2)), mapping_(mapping) {}
  Rgb eval(const TextureContext& ctx) const override;

 private:
  TexturePtr tex1_, tex2_;
  UvMapping mapping_;
};

// Product of two textures (pbrt-v4 "scale": tex * scale).
class ScaleTexture final : public Texture {
 public:
  ScaleTexture(TexturePtr tex, TexturePtr scale) : tex_(std::move(tex)), scale_(std::move(scale)) {}
  Rgb eval(const TextureContext& ctx) const override { return tex_->eval(ctx) * scale_->eval(ctx); }

 private:
  TexturePtr tex_, scale_;
};

inline TexturePtr make_constant_texture(Rgb v) { return std::make_shared<ConstantTexture>(v); }

}  // namespace caustica
