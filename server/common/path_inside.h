// Whether one path lies inside another, component by component: the jail
// check of the data root and of a reader's read root. Both paths must
// already be canonical (std::filesystem::canonical or weakly_canonical):
// this compares names, it resolves nothing.
#pragma once

#include <algorithm>
#include <filesystem>

namespace vpm {

// True when `inner` is `root` or lies under it ("/data" holds "/data/a" but
// not "/data2/a").
inline bool PathIsInside(const std::filesystem::path& root, const std::filesystem::path& inner) {
  const auto [root_end, inner_at] =
      std::mismatch(root.begin(), root.end(), inner.begin(), inner.end());
  return root_end == root.end();
}

}  // namespace vpm
