#include "server/mesh/monotone_min_queue.h"

#include <algorithm>
#include <bit>
#include <cstring>

namespace vpm {

MonotoneMinQueue::Key MonotoneMinQueue::KeyOf(const Entry& e) {
  const double cost = e.cost + 0.0;  // -0 -> +0: they compare equal as doubles
  uint64_t bits;
  std::memcpy(&bits, &cost, sizeof bits);
  return {bits, static_cast<uint32_t>(e.item)};
}

// 0: equal to the last key popped; 1..32: differs first in bit b-1 of the
// item; 33..96: in bit b-33 of the cost.
int MonotoneMinQueue::BucketOf(const Entry& e) const {
  const Key k = KeyOf(e);
  if (k.hi != last_.hi) return 33 + (63 - std::countl_zero(k.hi ^ last_.hi));
  if (k.lo != last_.lo) return 1 + (31 - std::countl_zero(k.lo ^ last_.lo));
  return 0;
}

void MonotoneMinQueue::Push(double cost, int32_t item) {
  const Entry e{cost, item};
  Add(BucketOf(e), e);
  ++size_;
}

int MonotoneMinQueue::FirstNonEmptyAboveZero() const {
  const uint64_t low = non_empty_[0] & ~uint64_t{1};
  return low != 0 ? std::countr_zero(low) : 64 + std::countr_zero(non_empty_[1]);
}

void MonotoneMinQueue::Split(int b) {
  std::vector<Entry>& from = buckets_[b];
  Key smallest = KeyOf(from.front());
  for (const Entry& e : from) {
    const Key k = KeyOf(e);
    if (KeyLess(k, smallest)) smallest = k;
  }
  last_ = smallest;
  // Every key of bucket b now differs from last_ in a lower bit than b's.
  std::vector<Entry> moving;
  moving.swap(from);
  MarkEmpty(b);
  for (const Entry& e : moving) Add(BucketOf(e), e);
  moving.clear();
  if (from.capacity() == 0) from.swap(moving);  // keep the allocation
}

void MonotoneMinQueue::PopRun(std::vector<Entry>* run) {
  if (buckets_[0].empty()) {
    const int b = FirstNonEmptyAboveZero();
    std::vector<Entry>& first = buckets_[b];
    if (first.size() > kMaxRun) {
      Split(b);
    } else {
      // Bucket b's keys are all below every other bucket's; taking them all
      // makes the largest of them the last popped, and every key left still
      // differs from it first in the bit of its bucket (b is the lowest).
      std::sort(first.begin(), first.end(),
                [](const Entry& x, const Entry& y) { return KeyLess(KeyOf(x), KeyOf(y)); });
      last_ = KeyOf(first.back());
      run->insert(run->end(), first.begin(), first.end());
      size_ -= static_cast<int64_t>(first.size());
      first.clear();
      MarkEmpty(b);
      return;
    }
  }
  // Keys equal to last_ (the smallest).
  std::vector<Entry>& equal = buckets_[0];
  run->insert(run->end(), equal.begin(), equal.end());
  size_ -= static_cast<int64_t>(equal.size());
  equal.clear();
  MarkEmpty(0);
}

const MonotoneMinQueue::Entry& MonotoneMinQueue::Top() {
  if (buckets_[0].empty()) Refill();
  return buckets_[0].back();
}

void MonotoneMinQueue::Pop() {
  if (buckets_[0].empty()) Refill();
  buckets_[0].pop_back();
  if (buckets_[0].empty()) MarkEmpty(0);
  --size_;
}

}  // namespace vpm
