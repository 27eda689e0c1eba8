// A binary min-heap over items 0..n-1 keyed by (cost, item): the smallest
// cost first, ties to the smaller item, as ALGORITHM.md step 2 orders
// removals. Each item's position is tracked, so Update moves an item in
// O(log n) whether its cost went up or down, and no stale entries pile up.
#pragma once

#include <cstdint>
#include <vector>

namespace vpm {

class IndexedMinHeap {
 public:
  // All n items with their initial costs; O(n) heapify.
  explicit IndexedMinHeap(std::vector<double> costs);

  bool empty() const { return heap_.empty(); }
  int64_t size() const { return static_cast<int64_t>(heap_.size()); }
  bool contains(int64_t item) const { return pos_[item] >= 0; }
  double cost(int64_t item) const { return cost_[item]; }
  int64_t top() const { return heap_.front(); }

  int64_t Pop();  // removes and returns the smallest item
  void Update(int64_t item, double cost);  // item must be contained

 private:
  bool Less(int64_t a, int64_t b) const {
    return cost_[a] < cost_[b] || (cost_[a] == cost_[b] && a < b);
  }
  void SiftUp(int64_t slot);
  void SiftDown(int64_t slot);
  void Place(int64_t slot, int64_t item) {
    heap_[slot] = item;
    pos_[item] = slot;
  }

  std::vector<double> cost_;   // by item
  std::vector<int64_t> pos_;   // slot of item in heap_, -1 once popped
  std::vector<int64_t> heap_;  // items
};

}  // namespace vpm
