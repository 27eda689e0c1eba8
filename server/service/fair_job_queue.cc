#include "server/service/fair_job_queue.h"

#include <algorithm>

namespace vpm::service {

void FairJobQueue::PurgeGone(std::deque<Job>& lane, std::vector<Job>* dropped) {
  auto keep = std::stable_partition(lane.begin(), lane.end(),
                                    [](const Job& j) { return !(j.gone && j.gone()); });
  for (auto it = keep; it != lane.end(); ++it) dropped->push_back(std::move(*it));
  size_ -= lane.end() - keep;
  lane.erase(keep, lane.end());
}

Status FairJobQueue::Push(Job&& job, std::vector<Job>* dropped) {
  auto full = [&] {
    auto it = lanes_.find(job.lane);
    const int64_t in_lane = it == lanes_.end() ? 0 : static_cast<int64_t>(it->second.size());
    return job.capped && ((limits_.max_per_lane > 0 && in_lane >= limits_.max_per_lane) ||
                          (limits_.max_total > 0 && size_ >= limits_.max_total));
  };
  if (full()) {
    for (auto it = lanes_.begin(); it != lanes_.end();) {
      PurgeGone(it->second, dropped);
      if (it->second.empty()) {
        turn_.remove(it->first);
        it = lanes_.erase(it);
      } else {
        ++it;
      }
    }
  }
  if (full()) {
    auto it = lanes_.find(job.lane);
    const int64_t in_lane = it == lanes_.end() ? 0 : static_cast<int64_t>(it->second.size());
    return absl::ResourceExhaustedError(
        limits_.max_per_lane > 0 && in_lane >= limits_.max_per_lane
            ? StrCat("queue full: ", in_lane, " of your calls are waiting (the cap is ",
                     limits_.max_per_lane, ")")
            : StrCat("queue full: ", size_, " calls are waiting on the server (the cap is ",
                     limits_.max_total, ")"));
  }
  auto [it, added] = lanes_.try_emplace(job.lane);
  if (added) turn_.push_back(job.lane);
  it->second.push_back(std::move(job));
  ++size_;
  return absl::OkStatus();
}

bool FairJobQueue::Pop(Job* job) {
  // The first lane in turn that may run one more job.
  auto at = std::find_if(turn_.begin(), turn_.end(), [&](const std::string& lane) {
    return limits_.max_running_per_lane <= 0 || !lanes_.at(lane).front().capped ||
           running(lane) < limits_.max_running_per_lane;
  });
  if (at == turn_.end()) return false;
  const std::string lane = std::move(*at);
  turn_.erase(at);
  auto it = lanes_.find(lane);
  *job = std::move(it->second.front());
  it->second.pop_front();
  --size_;
  if (job->capped) ++running_[lane];
  if (it->second.empty()) {
    lanes_.erase(it);
  } else {
    turn_.push_back(lane);  // back of the line
  }
  return true;
}

void FairJobQueue::Finished(const std::string& lane, bool capped) {
  if (!capped) return;
  auto it = running_.find(lane);
  if (it != running_.end() && --it->second <= 0) running_.erase(it);
}

int64_t FairJobQueue::running(const std::string& lane) const {
  auto it = running_.find(lane);
  return it == running_.end() ? 0 : it->second;
}

std::vector<Job> FairJobQueue::TakeAll() {
  std::vector<Job> all;
  for (const std::string& lane : turn_) {
    for (Job& job : lanes_[lane]) all.push_back(std::move(job));
  }
  lanes_.clear();
  turn_.clear();
  size_ = 0;
  return all;
}

int64_t FairJobQueue::lane_size(const std::string& lane) const {
  auto it = lanes_.find(lane);
  return it == lanes_.end() ? 0 : static_cast<int64_t>(it->second.size());
}

}  // namespace vpm::service
