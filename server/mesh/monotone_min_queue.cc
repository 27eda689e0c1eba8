#include "server/mesh/monotone_min_queue.h"

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
  buckets_[BucketOf(e)].push_back(e);
  ++size_;
}

void MonotoneMinQueue::Refill() {
  int b = 1;
  while (buckets_[b].empty()) ++b;
  std::vector<Entry>& from = buckets_[b];
  Key smallest = KeyOf(from.front());
  for (const Entry& e : from) {
    const Key k = KeyOf(e);
    if (k.hi < smallest.hi || (k.hi == smallest.hi && k.lo < smallest.lo)) smallest = k;
  }
  last_ = smallest;
  // Every key of bucket b now differs from last_ in a lower bit than b's.
  std::vector<Entry> moving;
  moving.swap(from);
  for (const Entry& e : moving) buckets_[BucketOf(e)].push_back(e);
  moving.clear();
  if (from.capacity() == 0) from.swap(moving);  // keep the allocation
}

const MonotoneMinQueue::Entry& MonotoneMinQueue::Top() {
  if (buckets_[0].empty()) Refill();
  return buckets_[0].back();
}

void MonotoneMinQueue::Pop() {
  if (buckets_[0].empty()) Refill();
  buckets_[0].pop_back();
  --size_;
}

}  // namespace vpm
