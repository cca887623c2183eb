// The guiding records of one training iteration, written by the rendering threads and read
// back in pixel order without a merged copy. Threads fill fixed-size blocks taken from one shared
// pool; each recorded pixel (a "slot": pixel / stride) notes where its records went, so runs()
// lists them in slot order, an order that does not depend on which thread rendered which pixel.
//
// Memory: the pool keeps its blocks between iterations and grows only when an iteration records
// more than any before, by whole blocks; its size is the largest iteration's records plus at
// most one partly filled block per thread, whatever the threads' shares of the pixels.
//
// Contract: a slot's records are appended by one thread, one after the other (a pixel's path is
// traced by one thread, and nothing else is appended by that thread meanwhile), and a slot holds
// at most kBlock records.
#pragma once

#include <tbb/enumerable_thread_specific.h>

#include <algorithm>
#include <cassert>
#include <cstdint>
#include <memory>
#include <mutex>
#include <span>
#include <vector>

#include "guiding/guiding_field.h"

namespace caustica {

class PixelRecords {
 public:
  static constexpr uint32_t kBlock = 1u << 14;  // records per block (640 KiB)

 private:
  struct Run {
    GuidingRecord* first = nullptr;
    uint32_t count = 0;
  };
  struct Cursor {  // a thread's block and how much of it is used
    GuidingRecord* block = nullptr;
    uint32_t used = kBlock;
  };

 public:
  // Empties the blocks (keeping them) and makes room for `slots` recorded pixels.
  void begin_iteration(uint64_t slots) {
    for (Cursor& c : cursors_) c = Cursor{};
    next_block_ = 0;
    runs_.assign(slots, Run{});
  }

  // Appends a slot's records from one thread; look it up once per pixel.
  class Writer {
   public:
    void push(const GuidingRecord& r) {
      assert(run_->count < kBlock);
      if (cursor_->used == kBlock) {
        // A fresh block: this slot's records so far move along, so that its run stays whole.
        GuidingRecord* block = owner_->acquire_block();
        std::copy(run_->first, run_->first + run_->count, block);
        run_->first = block;
        cursor_->block = block;
        cursor_->used = run_->count;
      }
      if (run_->count == 0) run_->first = cursor_->block + cursor_->used;
      assert(run_->first + run_->count == cursor_->block + cursor_->used);
      std::construct_at(cursor_->block + cursor_->used++, r);
      ++run_->count;
    }

   private:
    friend class PixelRecords;
    const PixelRecords* owner_ = nullptr;
    Run* run_ = nullptr;
    Cursor* cursor_ = nullptr;
  };
  Writer writer(uint64_t slot) const {
    assert(slot < runs_.size());
    Writer w;
    w.owner_ = this;
    w.run_ = &runs_[slot];
    w.cursor_ = &cursors_.local();
    return w;
  }

  // The records, slot after slot (valid until the next begin_iteration).
  std::vector<std::span<const GuidingRecord>> runs() const {
    std::vector<std::span<const GuidingRecord>> out;
    out.reserve(runs_.size());
    for (const Run& r : runs_)
      if (r.count) out.emplace_back(r.first, r.count);
    return out;
  }
  size_t size() const {
    size_t n = 0;
    for (const Run& r : runs_) n += r.count;
    return n;
  }
  size_t capacity_bytes() const {
    return runs_.capacity() * sizeof(Run) + blocks_.size() * kBlock * sizeof(GuidingRecord);
  }

 private:
  struct Free {
    void operator()(GuidingRecord* p) const { ::operator delete(p); }
  };
  // The next unused block of the pool, allocated (uninitialised) when the pool has none left.
  GuidingRecord* acquire_block() const {
    std::lock_guard<std::mutex> lock(mutex_);
    if (next_block_ == blocks_.size())
      blocks_.emplace_back(
          static_cast<GuidingRecord*>(::operator new(kBlock * sizeof(GuidingRecord))));
    return blocks_[next_block_++].get();
  }

  mutable tbb::enumerable_thread_specific<Cursor> cursors_;
  mutable std::vector<Run> runs_;
  mutable std::vector<std::unique_ptr<GuidingRecord, Free>> blocks_;
  mutable size_t next_block_ = 0;
  mutable std::mutex mutex_;
};

}  // namespace caustica
