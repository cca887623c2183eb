#include "geometry/texture.h"

#include <algorithm>
#include <cmath>
#include <stdexcept>

#include "image/image.h"

namespace caustica {

ImageTexture::ImageTexture(std::shared_ptr<const Image> image, UvMapping mapping, Rgb scale,
                           bool invert, bool first_channel, Image::Wrap wrap)
    : image_(std::move(image)),
      mapping_(mapping),
      scale_(scale),
      invert_(invert),
      first_channel_(first_channel),
      wrap_(wrap) {
  if (!image_ || image_->empty()) throw std::invalid_argument("ImageTexture: empty image");
}

Rgb ImageTexture::eval(const TextureContext& ctx) const {
  const Vec2 st = mapping_.map(ctx.uv);
  // Texture space has t = 0 at the bottom, the image stores its top row first: flip t, as
  // pbrt-v4's SpectrumImageTexture::Evaluate does.
  Rgb texel = image_->bilinear(st.x, 1.f - st.y, wrap_);
  if (first_channel_) texel = Rgb(texel.r);
  Rgb rgb = scale_ * texel;
  if (invert_) rgb = Rgb(1.f) - rgb;
  // pbrt-v4 clamps at zero after scale and invert, both with and without invert.
  return Rgb(std::max(rgb.r, 0.f), std::max(rgb.g, 0.f), std::max(rgb.b, 0.f));
}

Rgb CheckerboardTexture::eval(const TextureContext& ctx) const {
  const Vec2 st = mapping_.map(ctx.uv);
  // pbrt-v4's 2D Checkerboard() with a zero filter width: weight 0 (tex1) when floor(s) and
  // floor(t) have the same parity. Summing in double keeps large coordinates exact.
  const double sum = std::floor(double(st.x)) + std::floor(double(st.y));
  return std::fmod(sum, 2.0) == 0 ? tex1_->eval(ctx) : tex2_->eval(ctx);
}

}  // namespace caustica
