// Texture lookups: pbrt-v4 conventions for image textures and the 2D checkerboard.
#include "geometry/texture.h"

#include <gtest/gtest.h>

#include <memory>
#include <stdexcept>

#include "image/image.h"

namespace caustica {
namespace {

Rgb lookup(const Texture& texture, float u, float v) {
  TextureContext ctx;
  ctx.uv = Vec2(u, v);
  return texture.eval(ctx);
}

void expect_rgb_near(Rgb a, Rgb b, float tol = 1e-5f) {
  EXPECT_NEAR(a.r, b.r, tol);
  EXPECT_NEAR(a.g, b.g, tol);
  EXPECT_NEAR(a.b, b.b, tol);
}

// 4x2 image with a distinct value per texel; row 0 is the top of the image.
std::shared_ptr<const Image> four_by_two() {
  auto image = std::make_shared<Image>(4, 2);
  for (int y = 0; y < 2; ++y)
    for (int x = 0; x < 4; ++x) image->at(x, y) = Rgb(0.1f * x, 0.5f * y, 0.1f * x + 0.5f * y);
  return image;
}

TEST(Texture, ImageExactAtTexelCentres) {
  const auto image = four_by_two();
  const ImageTexture texture(image, UvMapping{});
  for (int y = 0; y < 2; ++y)
    for (int x = 0; x < 4; ++x)
      // Texel (x, y) counted from the top has its centre at v = 1 - (y + 0.5) / height.
      expect_rgb_near(lookup(texture, (x + 0.5f) / 4, 1 - (y + 0.5f) / 2), image->at(x, y));
}

TEST(Texture, ImageVZeroIsTheBottomRow) {
  auto image = std::make_shared<Image>(1, 2);
  image->at(0, 0) = Rgb(1, 0, 0);  // Top row.
  image->at(0, 1) = Rgb(0, 0, 1);  // Bottom row.
  const ImageTexture texture(image, UvMapping{});
  expect_rgb_near(lookup(texture, 0.5f, 0.25f), Rgb(0, 0, 1));
  expect_rgb_near(lookup(texture, 0.5f, 0.75f), Rgb(1, 0, 0));
  expect_rgb_near(lookup(texture, 0.5f, 0.5f), Rgb(0.5f, 0, 0.5f));  // Halfway between.
}

TEST(Texture, ImageBilinearBetweenCentres) {
  const auto image = four_by_two();
  const ImageTexture texture(image, UvMapping{});
  // Midway between texels (1, 0) and (2, 0) horizontally, on the top row's centre line.
  expect_rgb_near(lookup(texture, 0.5f, 0.75f), (image->at(1, 0) + image->at(2, 0)) * 0.5f);
  // Centre of the image: average of the four middle texels.
  expect_rgb_near(lookup(texture, 0.5f, 0.5f),
                  (image->at(1, 0) + image->at(2, 0) + image->at(1, 1) + image->at(2, 1)) * 0.25f);
}

TEST(Texture, ImageRepeatsOutsideUnitSquare) {
  const auto image = four_by_two();
  const ImageTexture texture(image, UvMapping{});
  for (float u : {0.1f, 0.37f, 0.9f})
    for (float v : {0.05f, 0.5f, 0.8f}) {
      const Rgb base = lookup(texture, u, v);
      expect_rgb_near(lookup(texture, u + 3, v), base);
      expect_rgb_near(lookup(texture, u - 2, v + 5), base);
      expect_rgb_near(lookup(texture, u, v - 1), base);
    }
  // Across the u = 0 seam the lookup blends the last and first columns.
  expect_rgb_near(lookup(texture, 0.f, 0.75f), (image->at(0, 0) + image->at(3, 0)) * 0.5f);
}

TEST(Texture, ImageUvScaleAndOffset) {
  auto image = std::make_shared<Image>(2, 1);
  image->at(0, 0) = Rgb(1.f);
  image->at(1, 0) = Rgb(2.f);
  UvMapping twice;
  twice.su = 2;
  const ImageTexture scaled(image, twice);
  expect_rgb_near(lookup(scaled, 0.125f, 0.5f), Rgb(1.f));  // s = 0.25
  expect_rgb_near(lookup(scaled, 0.375f, 0.5f), Rgb(2.f));  // s = 0.75
  expect_rgb_near(lookup(scaled, 0.625f, 0.5f), Rgb(1.f));  // s = 1.25: second repetition
  UvMapping shifted;
  shifted.du = 0.5f;
  const ImageTexture offset(image, shifted);
  expect_rgb_near(lookup(offset, 0.25f, 0.5f), Rgb(2.f));  // s = 0.75
  UvMapping flipped_v;
  flipped_v.sv = -1;
  auto column = std::make_shared<Image>(1, 2);
  column->at(0, 0) = Rgb(1.f);  // Top.
  column->at(0, 1) = Rgb(2.f);  // Bottom.
  const ImageTexture mirrored(column, flipped_v);
  expect_rgb_near(lookup(mirrored, 0.5f, 0.25f), Rgb(1.f));  // t = -0.25 wraps to 0.75: top.
}

TEST(Texture, ImageScaleAndInvertFollowPbrt) {
  auto image = std::make_shared<Image>(1, 1, Rgb(0.25f, 0.25f, 0.8f));
  const ImageTexture scaled(image, UvMapping{}, Rgb(2.f, 0.5f, 1.f));
  expect_rgb_near(lookup(scaled, 0.3f, 0.6f), Rgb(0.5f, 0.125f, 0.8f));
  // invert applies after scale and the result is clamped at zero: 1 - 2 * 0.8 < 0.
  const ImageTexture inverted(image, UvMapping{}, Rgb(2.f, 0.5f, 2.f), /*invert=*/true);
  expect_rgb_near(lookup(inverted, 0.3f, 0.6f), Rgb(0.5f, 0.875f, 0.f));
  // Negative texels are clamped too.
  auto negative = std::make_shared<Image>(1, 1, Rgb(-1.f, 0.5f, 1.f));
  expect_rgb_near(lookup(ImageTexture(negative, UvMapping{}), 0.5f, 0.5f), Rgb(0.f, 0.5f, 1.f));
}

TEST(Texture, ImageRejectsEmptyImage) {
  EXPECT_THROW(ImageTexture(nullptr, UvMapping{}), std::invalid_argument);
  EXPECT_THROW(ImageTexture(std::make_shared<Image>(), UvMapping{}), std::invalid_argument);
}

TEST(Texture, CheckerboardParity) {
  const Rgb a(1, 0, 0), b(0, 0, 1);
  const CheckerboardTexture board(make_constant_texture(a), make_constant_texture(b), UvMapping{});
  EXPECT_EQ(lookup(board, 0.5f, 0.5f), a);    // floor sum 0
  EXPECT_EQ(lookup(board, 1.5f, 0.5f), b);    // 1
  EXPECT_EQ(lookup(board, 1.5f, 1.5f), a);    // 2
  EXPECT_EQ(lookup(board, 0.5f, 2.5f), a);    // 2
  EXPECT_EQ(lookup(board, -0.5f, 0.5f), b);   // -1: odd below zero too
  EXPECT_EQ(lookup(board, -0.5f, -0.5f), a);  // -2
  EXPECT_EQ(lookup(board, 1.0f, 0.0f), b);    // Edges belong to the square above/right.
  EXPECT_EQ(lookup(board, 1e6f + 1, 0.5f), b);
  EXPECT_FALSE(board.is_constant());
}

TEST(Texture, CheckerboardUsesMapping) {
  const Rgb a(1.f), b(0.f);
  UvMapping mapping;
  mapping.su = 4;
  mapping.sv = 4;
  const CheckerboardTexture board(make_constant_texture(a), make_constant_texture(b), mapping);
  EXPECT_EQ(lookup(board, 0.1f, 0.1f), a);  // (0.4, 0.4)
  EXPECT_EQ(lookup(board, 0.3f, 0.1f), b);  // (1.2, 0.4)
  EXPECT_EQ(lookup(board, 0.3f, 0.3f), a);  // (1.2, 1.2)
  EXPECT_EQ(lookup(board, 0.6f, 0.1f), a);  // (2.4, 0.4)
}

TEST(Texture, CheckerboardEvaluatesNestedTextures) {
  auto image = std::make_shared<Image>(1, 1, Rgb(0.3f));
  const CheckerboardTexture board(std::make_shared<ImageTexture>(image, UvMapping{}),
                                  make_constant_texture(Rgb(0.9f)), UvMapping{});
  expect_rgb_near(lookup(board, 0.2f, 0.7f), Rgb(0.3f));
  expect_rgb_near(lookup(board, 1.2f, 0.7f), Rgb(0.9f));
}

// pbrt-v4's float image textures read the first channel of an RGB image (its MIP map's Texel<Float>
// is channel 0), not the mean of the three.
TEST(Texture, FloatImageTexturesReadTheFirstChannel) {
  auto image = std::make_shared<Image>(1, 1);
  image->at(0, 0) = Rgb(0.2f, 0.6f, 1.0f);
  const ImageTexture spectrum(image, {}), scalar(image, {}, Rgb(1.f), false, true);
  EXPECT_NEAR(spectrum.eval_float({{0.5f, 0.5f}, {}}), 0.6f, 1e-6f);
  EXPECT_NEAR(scalar.eval_float({{0.5f, 0.5f}, {}}), 0.2f, 1e-6f);
}

// pbrt-v4's wrap modes beyond repeat: clamp repeats the edge texels, black reads 0 outside. A
// 2 x 1 image (0 then 1): at s = 0.9 repeat blends the right texel with the left one across the
// seam, clamp keeps the right one, black fades it toward 0; far outside, clamp is the edge.
TEST(Texture, WrapModesRepeatClampAndBlack) {
  auto image = std::make_shared<Image>(2, 1);
  image->at(0, 0) = Rgb(0.f);
  image->at(1, 0) = Rgb(1.f);
  auto at = [&](Image::Wrap wrap, float s) {
    return ImageTexture(image, {}, Rgb(1.f), false, false, wrap).eval_float({{s, 0.5f}, {}});
  };
  EXPECT_NEAR(at(Image::Wrap::Repeat, 0.9f), 0.7f, 1e-5f);
  EXPECT_NEAR(at(Image::Wrap::Clamp, 0.9f), 1.f, 1e-5f);
  EXPECT_NEAR(at(Image::Wrap::Black, 0.9f), 0.7f, 1e-5f);
  EXPECT_NEAR(at(Image::Wrap::Black, 0.1f), 0.f, 1e-5f);
  EXPECT_NEAR(at(Image::Wrap::Clamp, 0.1f), 0.f, 1e-5f);
  EXPECT_NEAR(at(Image::Wrap::Repeat, 0.1f), 0.3f, 1e-5f);
  EXPECT_NEAR(at(Image::Wrap::Clamp, 1e9f), 1.f, 1e-5f);
  EXPECT_NEAR(at(Image::Wrap::Black, -1e9f), 0.f, 1e-5f);
  EXPECT_NEAR(at(Image::Wrap::Black, 0.75f), 1.f, 1e-5f);  // a texel centre is exact
}

}  // namespace
}  // namespace caustica
