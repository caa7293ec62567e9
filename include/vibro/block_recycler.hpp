// An allocator that keeps the element blocks a node-based container frees and hands them back on
// its next allocations (docs/performance.md, "Probes per event"). The attractor recorder's event log
// is a std::deque of 120-byte events: a 480-byte node every four events, allocated at the back as
// the run goes and freed at the front a period at a time as the window slides, so that malloc and
// free took 3–4 % of a 1-DOF run (glibc's per-thread cache holds 7 blocks of a size; a period of
// Fig. 8 frees 9). The recycled blocks are bounded (kMaxBlocks), so the memory held beyond the
// container's own is at most kMaxBlocks nodes; blocks of another size (the deque's map of node
// pointers) go to the global operator new and delete as before.
#pragma once

#include <cstddef>
#include <memory>
#include <new>
#include <type_traits>
#include <vector>

namespace vibro {

namespace detail {

// The free blocks of one container: all of one size, the first size freed.
class BlockCache {
 public:
  static constexpr std::size_t kMaxBlocks = 64;
  BlockCache() = default;
  BlockCache(const BlockCache&) = delete;
  BlockCache& operator=(const BlockCache&) = delete;
  ~BlockCache() {
    for (void* p : free_) ::operator delete(p, bytes_);
  }
  void* Get(std::size_t bytes) {
    if (bytes == bytes_ && !free_.empty()) {
      void* p = free_.back();
      free_.pop_back();
      return p;
    }
    return ::operator new(bytes);
  }
  void Put(void* p, std::size_t bytes) noexcept {
    if (bytes_ == 0) {
      bytes_ = bytes;
      try {
        free_.reserve(kMaxBlocks);
      } catch (...) {  // no room for the list: blocks are simply freed
      }
    }
    if (bytes == bytes_ && free_.size() < free_.capacity()) {
      free_.push_back(p);  // within capacity: no allocation, no throw
      return;
    }
    ::operator delete(p, bytes);
  }

 private:
  std::size_t bytes_ = 0;
  std::vector<void*> free_;
};

}  // namespace detail

// Recycles the blocks of elements of type Elem (a deque's nodes); every rebound copy (the deque's
// map of pointers to nodes) shares the cache and allocates as std::allocator does. A copy of the
// container gets a cache of its own (the cache is not shared between containers, nor threads).
template <class T, class Elem = T>
class BlockRecycler {
 public:
  using value_type = T;
  using propagate_on_container_move_assignment = std::true_type;
  using propagate_on_container_swap = std::true_type;
  using is_always_equal = std::false_type;
  template <class U>
  struct rebind {
    using other = BlockRecycler<U, Elem>;
  };

  BlockRecycler() : cache_(std::make_shared<detail::BlockCache>()) {}
  template <class U>
  BlockRecycler(const BlockRecycler<U, Elem>& o) noexcept : cache_(o.cache_) {}  // NOLINT: rebind

  T* allocate(std::size_t n) {
    if constexpr (std::is_same_v<T, Elem>) return static_cast<T*>(cache_->Get(n * sizeof(T)));
    return static_cast<T*>(::operator new(n * sizeof(T)));
  }
  void deallocate(T* p, std::size_t n) noexcept {
    if constexpr (std::is_same_v<T, Elem>) cache_->Put(p, n * sizeof(T));
    else ::operator delete(p, n * sizeof(T));
  }
  BlockRecycler select_on_container_copy_construction() const { return BlockRecycler(); }

  template <class U>
  bool operator==(const BlockRecycler<U, Elem>& o) const noexcept {
    return cache_ == o.cache_;
  }

 private:
  template <class, class>
  friend class BlockRecycler;
  std::shared_ptr<detail::BlockCache> cache_;
};

}  // namespace vibro
