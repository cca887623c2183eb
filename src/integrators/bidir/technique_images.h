// The per-technique images of the bidirectional core (--techniques DIR): one MIS-weighted image
// per (s, t) connection technique and per merge depth; they add up to the rendered image.
#pragma once

#include <array>
#include <atomic>
#include <cstdint>
#include <memory>
#include <mutex>
#include <string>
#include <vector>

#include "core/rgb.h"
#include "image/image.h"

namespace caustica::bidir {

// One image per technique, allocated on first use. Key: (merge, s, t) with s light vertices
// (the light point included) and t camera vertices (the lens included); a merge at a vertex
// counts that vertex on both sides.
class TechniqueImages {
 public:
  static constexpr int kMaxVertices = 64;
  static uint32_t key(bool merge, int s, int t) {
    return (merge ? kMaxVertices * kMaxVertices : 0) +
           uint32_t(std::min(s, kMaxVertices - 1)) * kMaxVertices +
           uint32_t(std::min(t, kMaxVertices - 1));
  }
  void reset(int width, int height) {
    width_ = width;
    height_ = height;
    for (auto& s : slots_) s.reset();
    for (auto& p : pointers_) p.store(nullptr);
  }
  bool enabled() const { return width_ > 0; }
  void add(uint32_t key, size_t pixel, Rgb value) {
    Image* image = pointers_[key].load(std::memory_order_acquire);
    if (!image) {
      std::lock_guard<std::mutex> lock(mutex_);
      if (!slots_[key]) {
        slots_[key] = std::make_unique<Image>(width_, height_);
        pointers_[key].store(slots_[key].get(), std::memory_order_release);
      }
      image = slots_[key].get();
    }
    (*image)[pixel] += value;
  }
  // Writes each technique averaged over `iterations` to DIR/{connect,merge}_sS_tT.exr; returns
  // the files written.
  std::vector<std::string> write(const std::string& dir, uint32_t iterations) const;

 private:
  int width_ = 0, height_ = 0;
  std::mutex mutex_;
  std::array<std::unique_ptr<Image>, 2 * kMaxVertices * kMaxVertices> slots_;
  std::array<std::atomic<Image*>, 2 * kMaxVertices * kMaxVertices> pointers_{};
};

}  // namespace caustica::bidir
