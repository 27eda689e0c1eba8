// A monotone priority queue (a radix heap) of (cost, item) keys: the
// smallest cost first, ties to the smaller item, for step 2 in `spread` mode
// (docs/ALGORITHM.md), where a removal only ever raises the costs of the vertices
// left, so every key pushed is at least the last one popped. Under that
// promise it pops exactly what IndexedMinHeap would, with sequential memory
// traffic instead of a sift through a large tree: a key waits in the bucket
// of the highest bit in which it differs from the last key popped, and
// buckets are only ever scanned and split front to back. A bitmask of the
// non-empty buckets finds the first without a scan.
#pragma once

#include <array>
#include <cstddef>
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
  // Pops the smallest keys, at least one and at most kMaxRun, appending them
  // to run in ascending order: the whole first bucket when it is that small
  // (one sort instead of a split per bit left), else the smallest key alone.
  // The queue must not be empty.
  void PopRun(std::vector<Entry>* run);

  static constexpr size_t kMaxRun = 32;

 private:
  // The order of keys as one 96-bit unsigned number: cost bits (non-negative
  // doubles order as their bit patterns), then the item.
  struct Key {
    uint64_t hi;
    uint32_t lo;
  };
  static Key KeyOf(const Entry& e);
  static bool KeyLess(const Key& a, const Key& b) {
    return a.hi < b.hi || (a.hi == b.hi && a.lo < b.lo);
  }
  int BucketOf(const Entry& e) const;
  void Add(int bucket, const Entry& e) {
    buckets_[bucket].push_back(e);
    non_empty_[bucket >> 6] |= uint64_t{1} << (bucket & 63);
  }
  void MarkEmpty(int bucket) { non_empty_[bucket >> 6] &= ~(uint64_t{1} << (bucket & 63)); }
  int FirstNonEmptyAboveZero() const;  // some bucket 1..96 must hold a key
  // Makes the smallest key of bucket b (the first non-empty one) last_ and
  // moves b's keys down to the buckets they now belong to.
  void Split(int b);
  void Refill() { Split(FirstNonEmptyAboveZero()); }

  std::array<std::vector<Entry>, 97> buckets_;
  std::array<uint64_t, 2> non_empty_{0, 0};  // bit b: buckets_[b] holds a key
  Key last_{0, 0};
  int64_t size_ = 0;
};

}  // namespace vpm
