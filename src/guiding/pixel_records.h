// The guiding records of one training iteration, written by the rendering threads and read
// back in pixel order without a merged copy. Each thread appends to its own buffer; each recorded
// pixel (a "slot": pixel / stride) notes where its records went, so runs() lists them in slot
// order, an order that does not depend on which thread rendered which pixel.
//
// Contract: a slot's records are appended by one thread, one after the other (a pixel's path
// is traced by one thread, and nothing else is appended to that thread's buffer meanwhile).
#pragma once

#include <tbb/enumerable_thread_specific.h>

#include <cassert>
#include <cstdint>
#include <span>
#include <vector>

#include "guiding/guiding_field.h"

namespace caustica {

class PixelRecords {
  struct Run {
    std::vector<GuidingRecord>* buffer = nullptr;
    uint32_t begin = 0, count = 0;
  };

 public:
  // Empties the buffers (keeping their memory) and makes room for `slots` recorded pixels.
  void begin_iteration(uint64_t slots) {
    for (std::vector<GuidingRecord>& b : buffers_) b.clear();
    runs_.assign(slots, Run{});
  }

  // Appends a slot's records from one thread; look it up once per pixel.
  class Writer {
   public:
    void push(const GuidingRecord& r) {
      if (!run_->buffer) *run_ = {buffer_, uint32_t(buffer_->size()), 0};
      assert(run_->buffer == buffer_ && run_->begin + run_->count == buffer_->size());
      buffer_->push_back(r);
      ++run_->count;
    }

   private:
    friend class PixelRecords;
    Run* run_ = nullptr;
    std::vector<GuidingRecord>* buffer_ = nullptr;
  };
  Writer writer(uint64_t slot) const {
    assert(slot < runs_.size());
    Writer w;
    w.run_ = &runs_[slot];
    w.buffer_ = &buffers_.local();
    return w;
  }

  // The records, slot after slot (valid until the next begin_iteration or writer()).
  std::vector<std::span<const GuidingRecord>> runs() const {
    std::vector<std::span<const GuidingRecord>> out;
    out.reserve(runs_.size());
    for (const Run& r : runs_)
      if (r.count) out.emplace_back(r.buffer->data() + r.begin, r.count);
    return out;
  }
  size_t size() const {
    size_t n = 0;
    for (const std::vector<GuidingRecord>& b : buffers_) n += b.size();
    return n;
  }
  size_t capacity_bytes() const {
    size_t bytes = runs_.capacity() * sizeof(Run);
    for (const std::vector<GuidingRecord>& b : buffers_)
      bytes += b.capacity() * sizeof(GuidingRecord);
    return bytes;
  }

 private:
  mutable tbb::enumerable_thread_specific<std::vector<GuidingRecord>> buffers_;
  mutable std::vector<Run> runs_;
};

}  // namespace caustica
