// A monotone priority queue (a radix heap) of (cost, item) keys: the
// smallest cost first, ties to the smaller item, for step 2 in `spread` mode
// (ALGORITHM.md), where a removal only ever raises the costs of the vertices
// left, so every key pushed is at least the last one popped. Under that
// promise it pops exactly what IndexedMinHeap would, with sequential memory
// traffic instead of a sift through a large tree: a key waits in the bucket
// of the highest bit in which it differs from the last key popped, and
// buckets are only ever scanned and split front to back.
#pragma once

#include <array>
#include <cstdint>
#include <vector>

namespace vpm {

class MonotoneMinQueue {
 public:
  struct Entry {
    double cost;  // >= 0 and finite
    int32_t item;
  };

  bool empty() const { return size_ == 0; }
  int64_t size() const { return size_; }

  // cost must be finite, >= 0 and, with item, not below the last popped key.
  void Push(double cost, int32_t item);
  // The smallest key; the queue must not be empty.
  const Entry& Top();
  void Pop();

 private:
  // The order of keys as one 96-bit unsigned number: cost bits (non-negative
  // doubles order as their bit patterns), then the item.
  struct Key {
    uint64_t hi;
    uint32_t lo;
  };
  static Key KeyOf(const Entry& e);
  int BucketOf(const Entry& e) const;
  void Refill();  // moves the smallest non-empty bucket's keys down

  std::array<std::vector<Entry>, 97> buckets_;
  Key last_{0, 0};
  int64_t size_ = 0;
};

}  // namespace vpm
