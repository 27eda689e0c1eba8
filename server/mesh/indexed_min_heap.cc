#include "server/mesh/indexed_min_heap.h"

#include <cstddef>

namespace vpm {

IndexedMinHeap::IndexedMinHeap(const std::vector<double>& costs)
    : size_(static_cast<int64_t>(costs.size())),
      storage_(new Entry[costs.size() + 2 * kArity]),
      pos_(costs.size()) {
  // Align base_ to kArity entries (new[] gives 16 bytes, one entry).
  constexpr std::uintptr_t kAlign = kArity * sizeof(Entry);
  const auto address = reinterpret_cast<std::uintptr_t>(storage_.get());
  base_ = storage_.get() + ((kAlign - address % kAlign) % kAlign) / sizeof(Entry);
  for (int64_t i = 0; i < size_; ++i) Place(i, {costs[i], static_cast<int32_t>(i)});
  for (int64_t slot = (size_ - 2) / kArity; slot >= 0 && size_ > 1; --slot) {
    SiftDown(slot, At(slot));
  }
}

int64_t IndexedMinHeap::Pop() {
  const int64_t item = At(0).item;
  pos_[item] = -1;
  --size_;
  if (size_ > 0) SiftDown(0, At(size_));
  return item;
}

void IndexedMinHeap::Update(int64_t item, double cost) {
  const int64_t slot = pos_[item];
  const Entry old = At(slot);
  const Entry e{cost, old.item};
  if (Less(e, old)) {
    SiftUp(slot, e);
  } else {
    SiftDown(slot, e);
  }
}

void IndexedMinHeap::SiftUp(int64_t slot, Entry e) {
  while (slot > 0) {
    const int64_t parent = (slot - 1) / kArity;
    if (!Less(e, At(parent))) break;
    Place(slot, At(parent));
    slot = parent;
  }
  Place(slot, e);
}

void IndexedMinHeap::SiftDown(int64_t slot, Entry e) {
  while (true) {
    const int64_t first = kArity * slot + 1;
    if (first >= size_) break;
    const int64_t last = first + kArity < size_ ? first + kArity : size_;
    int64_t best = first;
    for (int64_t c = first + 1; c < last; ++c) {
      if (Less(At(c), At(best))) best = c;
    }
    if (!Less(At(best), e)) break;
    Place(slot, At(best));
    slot = best;
  }
  Place(slot, e);
}

}  // namespace vpm
