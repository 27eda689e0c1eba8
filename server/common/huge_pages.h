// Memory the kernel is asked to back with transparent huge pages (2 MiB):
// HugePageArray for arrays read at random addresses, HugePageVector and
// AdviseHugePages for large buffers written once and read in order.
//
// Arrays read at random addresses (step 2's densities, costs, positions
// and neighbour lists at 1,000,000 vertices: some 200 MB): with 4 KiB pages
// nearly every access is a TLB miss; huge pages remove those (docs/MESH.md
// measures it). Buffers written once (a volume's voxels as a reader fills
// them, a GPU buffer's mapping on a CPU device): each 4 KiB page faults on
// its first write, in this VM for microseconds; with 2 MiB pages one fault
// covers 512 of them (docs/LAVAPIPE.md, "Huge pages"). The request is a
// hint: where transparent huge pages are off, or on other systems, the
// memory is ordinary.
#pragma once

#include <algorithm>
#include <cstddef>
#include <cstdint>
#include <cstdlib>
#include <cstring>
#include <memory>
#include <new>
#include <type_traits>
#include <vector>

#include <sys/mman.h>

namespace vpm {

inline constexpr size_t kHugePageBytes = size_t{2} << 20;

// Advises huge pages over the whole 2 MiB blocks inside [memory, memory +
// bytes), before they are first written (pages already present stay as they
// are). Only advice: a refusal changes nothing.
inline void AdviseHugePages(void* memory, size_t bytes) {
  constexpr uintptr_t kHuge = kHugePageBytes;
  const uintptr_t first = reinterpret_cast<uintptr_t>(memory);
  const uintptr_t begin = (first + kHuge - 1) & ~(kHuge - 1);
  const uintptr_t end = (first + bytes) & ~(kHuge - 1);
  if (end > begin) ::madvise(reinterpret_cast<void*>(begin), end - begin, MADV_HUGEPAGE);
}

// A vector of `count` value-initialized elements whose memory was advised
// huge pages before the initialization first wrote it (reserve allocates
// without writing; large allocations are fresh mappings).
template <typename T>
std::vector<T> HugePageVector(size_t count) {
  std::vector<T> v;
  v.reserve(count);
  AdviseHugePages(v.data(), count * sizeof(T));
  v.resize(count);
  return v;
}

template <typename T>
class HugePageArray {
  static_assert(std::is_trivially_copyable_v<T>);

 public:
  enum class Init { kZero, kNone };

  explicit HugePageArray(size_t size, Init init = Init::kZero) : size_(size) {
    const size_t bytes = std::max<size_t>(size * sizeof(T), 1);
    void* memory = nullptr;
    if (bytes >= kHugePageBytes) {
      const size_t rounded = (bytes + kHugePageBytes - 1) / kHugePageBytes * kHugePageBytes;
      memory = std::aligned_alloc(kHugePageBytes, rounded);
      if (memory != nullptr) AdviseHugePages(memory, rounded);
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
