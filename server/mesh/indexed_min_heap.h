// A 4-ary min-heap over items 0..n-1 keyed by (cost, item): the smallest
// cost first, ties to the smaller item, as docs/ALGORITHM.md step 2 orders
// removals. Each item's position is tracked, so Update moves an item in
// O(log n) whether its cost went up or down, and no stale entries pile up.
//
// Layout: keys live in the heap array next to their items (16-byte entries),
// and the four children of a slot share one 64-byte cache line, so a sift
// step costs one line instead of a line per compared item; with 4 children
// the tree is half as deep as a binary one (decimation of 1,000,000
// vertices: bench/mesh_build_bench.cc, docs/MESH.md).
#pragma once

#include <cstdint>
#include <memory>
#include <vector>

namespace vpm {

class IndexedMinHeap {
 public:
  // All n items with their initial costs (n < 2^31); O(n) heapify.
  explicit IndexedMinHeap(const std::vector<double>& costs);

  bool empty() const { return size_ == 0; }
  int64_t size() const { return size_; }
  bool contains(int64_t item) const { return pos_[item] >= 0; }
  double cost(int64_t item) const { return At(pos_[item]).cost; }
  int64_t top() const { return At(0).item; }
  double top_cost() const { return At(0).cost; }

  int64_t Pop();  // removes and returns the smallest item
  void Update(int64_t item, double cost);  // item must be contained

 private:
  struct Entry {
    double cost;
    int32_t item;
  };
  static_assert(sizeof(Entry) == 16);
  static bool Less(const Entry& a, const Entry& b) {
    return a.cost < b.cost || (a.cost == b.cost && a.item < b.item);
  }
  static constexpr int64_t kArity = 4;
  // Slot s is stored at base_[s + kArity - 1]: the children of s, slots
  // kArity s + 1 .. kArity s + kArity, then start at a multiple of kArity
  // entries from base_, which is aligned to kArity entries.
  Entry& At(int64_t slot) { return base_[slot + kArity - 1]; }
  const Entry& At(int64_t slot) const { return base_[slot + kArity - 1]; }
  void SiftUp(int64_t slot, Entry e);
  void SiftDown(int64_t slot, Entry e);
  void Place(int64_t slot, const Entry& e) {
    At(slot) = e;
    pos_[e.item] = static_cast<int32_t>(slot);
  }

  int64_t size_ = 0;
  std::unique_ptr<Entry[]> storage_;  // size_ + 3 entries + alignment slack
  Entry* base_ = nullptr;             // 64-byte aligned start within storage_
  std::vector<int32_t> pos_;          // slot of item, -1 once popped
};

}  // namespace vpm
