#include "server/mesh/indexed_min_heap.h"

#include <numeric>

namespace vpm {

IndexedMinHeap::IndexedMinHeap(std::vector<double> costs)
    : cost_(std::move(costs)), pos_(cost_.size()), heap_(cost_.size()) {
  std::iota(heap_.begin(), heap_.end(), 0);
  std::iota(pos_.begin(), pos_.end(), 0);
  for (int64_t slot = size() / 2 - 1; slot >= 0; --slot) SiftDown(slot);
}

int64_t IndexedMinHeap::Pop() {
  const int64_t item = heap_.front();
  const int64_t last = heap_.back();
  heap_.pop_back();
  pos_[item] = -1;
  if (!heap_.empty()) {
    Place(0, last);
    SiftDown(0);
  }
  return item;
}

void IndexedMinHeap::Update(int64_t item, double cost) {
  const double old = cost_[item];
  cost_[item] = cost;
  if (cost < old) {
    SiftUp(pos_[item]);
  } else {
    SiftDown(pos_[item]);
  }
}

void IndexedMinHeap::SiftUp(int64_t slot) {
  const int64_t item = heap_[slot];
  while (slot > 0) {
    const int64_t parent = (slot - 1) / 2;
    if (!Less(item, heap_[parent])) break;
    Place(slot, heap_[parent]);
    slot = parent;
  }
  Place(slot, item);
}

void IndexedMinHeap::SiftDown(int64_t slot) {
  const int64_t item = heap_[slot];
  const int64_t n = size();
  while (true) {
    int64_t child = 2 * slot + 1;
    if (child >= n) break;
    if (child + 1 < n && Less(heap_[child + 1], heap_[child])) ++child;
    if (!Less(heap_[child], item)) break;
    Place(slot, heap_[child]);
    slot = child;
  }
  Place(slot, item);
}

}  // namespace vpm
