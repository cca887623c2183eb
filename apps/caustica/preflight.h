// Checks against the machine and the file system that run before a scene is loaded or a render
// starts, so that a run which cannot succeed fails in milliseconds instead of after its render.
// Each returns "" when all is well, else a one-line reason that names the option involved.
#pragma once

#include <cstdint>
#include <string>

#include "image/image.h"

namespace caustica::cli {

// Bytes per pixel: film sums (3 doubles for the iteration, 24, and 3 16-byte fixed-point totals,
// 48; film.h), the averaged image (12), light-tracing splats
// (12), the tone-mapped copy (12), PNG bytes (~6) and the EXR encoding (12, its worst case).
constexpr uint64_t kFilmBytesPerPixel = 128;
// Bytes per light path: its start index (4), its end within a chunk (4) and at least one
// stored 32-byte light vertex.
constexpr uint64_t kBytesPerLightPath = 40;
// Pixels and light paths are indexed with 32-bit integers in the integrators.
constexpr uint64_t kMaxPixels = (uint64_t(1) << 31) - 1;
constexpr uint64_t kMaxLightPaths = (uint64_t(1) << 31) - 2;

// Physical memory (or the address-space limit, if lower), in bytes; 0 if unknown.
uint64_t memory_cap_bytes();

// Whether a width x height film with `light_paths` light paths per iteration (0: one per pixel,
// the default) fits in memory_cap_bytes() and in the 32-bit pixel index. A conservative lower
// bound on what the render needs: scene geometry and per-thread scratch come on top.
std::string film_memory_problem(int width, int height, uint64_t light_paths);

// A scene that names an existing path must be a regular file: a directory, a FIFO or a device
// would reach the loader as an unreadable or endless stream.
std::string scene_path_problem(const std::string& scene);

// --reference for compare: an existing regular file that reads as an image; fills *image.
std::string reference_problem(const std::string& path, Image* image);

}  // namespace caustica::cli
