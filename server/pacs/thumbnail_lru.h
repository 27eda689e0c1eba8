// The series thumbnails rendered lately, in memory, by endpoint, series UID
// and size: a Studies panel that lists a study again asks the PACS nothing.
// Least recently used out past `capacity` entries (a 128-pixel PNG is a few
// kB: 512 of them a few MB).
#pragma once

#include <cstddef>
#include <list>
#include <map>
#include <mutex>
#include <optional>
#include <string>

#include "server/pacs/series_thumbnail.h"

namespace vpm::pacs {

class ThumbnailLru {
 public:
  explicit ThumbnailLru(size_t capacity = 512) : capacity_(capacity) {}

  std::optional<SeriesThumbnail> Find(const std::string& key) {
    std::lock_guard lock(mutex_);
    auto it = entries_.find(key);
    if (it == entries_.end()) return std::nullopt;
    order_.splice(order_.begin(), order_, it->second.place);
    return it->second.thumbnail;
  }

  void Put(const std::string& key, SeriesThumbnail thumbnail) {
    std::lock_guard lock(mutex_);
    if (auto it = entries_.find(key); it != entries_.end()) {
      order_.erase(it->second.place);
      entries_.erase(it);
    }
    order_.push_front(key);
    entries_[key] = {std::move(thumbnail), order_.begin()};
    while (entries_.size() > capacity_) {
      entries_.erase(order_.back());
      order_.pop_back();
    }
  }

 private:
  struct Entry {
    SeriesThumbnail thumbnail;
    std::list<std::string>::iterator place;
  };
  const size_t capacity_;
  std::mutex mutex_;
  std::list<std::string> order_;  // most recent first
  std::map<std::string, Entry> entries_;
};

}  // namespace vpm::pacs
