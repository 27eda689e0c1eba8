// A fixed-size array of trivially copyable values whose memory the kernel is
// asked to back with transparent huge pages (2 MiB) when it is that large.
// For arrays read at random addresses (step 2's densities, costs, positions
// and neighbour lists at 1,000,000 vertices: some 200 MB), 4 KiB pages make
// nearly every access a TLB miss; huge pages remove those (docs/MESH.md
// measures it). The request is a hint: where THP is off, or on other
// systems, the array is ordinary memory.
#pragma once

#include <algorithm>
#include <cstddef>
#include <cstdlib>
#include <cstring>
#include <memory>
#include <new>
#include <type_traits>

#include <sys/mman.h>

namespace vpm {

template <typename T>
class HugePageArray {
  static_assert(std::is_trivially_copyable_v<T>);

 public:
  enum class Init { kZero, kNone };

  explicit HugePageArray(size_t size, Init init = Init::kZero) : size_(size) {
    constexpr size_t kHugePage = size_t{2} << 20;
    const size_t bytes = std::max<size_t>(size * sizeof(T), 1);
    void* memory = nullptr;
    if (bytes >= kHugePage) {
      const size_t rounded = (bytes + kHugePage - 1) / kHugePage * kHugePage;
      memory = std::aligned_alloc(kHugePage, rounded);
      if (memory != nullptr) ::madvise(memory, rounded, MADV_HUGEPAGE);  // a hint
    } else {
      memory = std::malloc(bytes);
    }
    if (memory == nullptr) throw std::bad_alloc();
    data_.reset(static_cast<T*>(memory));
    if (init == Init::kZero) std::memset(memory, 0, bytes);
  }

  size_t size() const { return size_; }
  T* data() { return data_.get(); }
  const T* data() const { return data_.get(); }
  T& operator[](size_t i) { return data_.get()[i]; }
  const T& operator[](size_t i) const { return data_.get()[i]; }
  T* begin() { return data(); }
  T* end() { return data() + size_; }
  const T* begin() const { return data(); }
  const T* end() const { return data() + size_; }

 private:
  struct Free {
    void operator()(T* p) const { std::free(p); }
  };
  size_t size_;
  std::unique_ptr<T, Free> data_;
};

}  // namespace vpm
