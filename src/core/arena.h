// A bump allocator for per-path scratch objects (BxDFs). One arena per worker task,
// reset between paths: hot loops allocate nothing after warm-up. Objects placed here must be
// trivially destructible (no destructor is ever run).
#pragma once

#include <cstddef>
#include <cstdlib>
#include <memory>
#include <new>
#include <type_traits>
#include <utility>
#include <vector>

namespace caustica {

class ScratchArena {
 public:
  explicit ScratchArena(size_t block_bytes = 16 * 1024) : block_bytes_(block_bytes) {
    grow(block_bytes);
  }
  ScratchArena(const ScratchArena&) = delete;
  ScratchArena& operator=(const ScratchArena&) = delete;

  template <typename T, typename... Args>
  T* make(Args&&... args) {
    static_assert(std::is_trivially_destructible_v<T>, "arena objects are never destroyed");
    void* mem = allocate(sizeof(T), alignof(T));
    return new (mem) T(std::forward<Args>(args)...);
  }

  void* allocate(size_t bytes, size_t align) {
    size_t offset = (used_ + align - 1) & ~(align - 1);
    if (offset + bytes > blocks_[current_].size) {
      if (++current_ == blocks_.size()) grow(std::max(bytes + align, block_bytes_));
      offset = 0;
    }
    used_ = offset + bytes;
    return blocks_[current_].data.get() + offset;
  }

  // Forget every allocation; memory is kept for reuse.
  void reset() {
    current_ = 0;
    used_ = 0;
  }

 private:
  static constexpr std::align_val_t kAlignment{64};
  // Memory from aligned operator new must go back through aligned operator delete.
  struct AlignedDelete {
    void operator()(std::byte* p) const { ::operator delete[](p, kAlignment); }
  };
  struct Block {
    std::unique_ptr<std::byte[], AlignedDelete> data;
    size_t size;
  };
  void grow(size_t bytes) {
    blocks_.push_back({std::unique_ptr<std::byte[], AlignedDelete>(
                           static_cast<std::byte*>(::operator new[](bytes, kAlignment))),
                       bytes});
    current_ = blocks_.size() - 1;
    used_ = 0;
  }
  size_t block_bytes_;
  std::vector<Block> blocks_;
  size_t current_ = 0, used_ = 0;
};

}  // namespace caustica
