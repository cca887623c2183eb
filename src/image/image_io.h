// Reading and writing images. Writers go through a temporary file and an atomic rename, so
// an interrupted run never leaves a truncated image. Errors throw std::runtime_error with a
// message that names the file.
#pragma once

#include <string>

#include "image/image.h"

namespace caustica {

// Reads EXR (linear), PFM (linear), PNG/JPEG/TGA/BMP/HDR via stb. 8-bit formats are decoded
// from sRGB to linear when `srgb` is true (pbrt-v4's default for PNG).
Image read_image(const std::string& path, bool srgb = true);

void write_exr(const Image& image, const std::string& path);
void write_pfm(const Image& image, const std::string& path);
// Writes an 8-bit sRGB PNG of an already tone-mapped image (values clamped to [0,1]).
void write_png_srgb(const Image& display_image, const std::string& path);

// Writes `contents` to `path` via a temporary file in the same directory and a rename.
void write_file_atomic(const std::string& path, const std::string& contents);

}  // namespace caustica
