// Errors as values: every fallible function returns absl::Status or
// absl::StatusOr<T> (`Result<T>`). The codes are gRPC's, so the service layer
// maps them one to one onto grpc::Status at the boundary.
#pragma once

#include <sstream>
#include <string>
#include <type_traits>
#include <utility>

#include "absl/status/status.h"
#include "absl/status/statusor.h"

namespace vpm {

using Status = absl::Status;
template <typename T>
using Result = absl::StatusOr<T>;

namespace internal {
// One-byte integers print as numbers, not as characters; char stays a
// character.
template <typename T>
decltype(auto) StrCatArg(const T& value) {
  if constexpr (std::is_integral_v<T> && sizeof(T) == 1 && !std::is_same_v<T, char> &&
                !std::is_same_v<T, bool>) {
    return static_cast<int>(value);
  } else {
    return (value);
  }
}
}  // namespace internal

// Concatenates anything streamable into a message; numbers as `operator<<`
// writes them (floating point with 6 significant digits). The project's one
// StrCat: Debian's abseil is built with its own string_view type, so
// absl::StrCat rejects std::string_view, and one-byte integers would print as
// characters through a plain stream.
template <typename... Args>
std::string StrCat(const Args&... args) {
  std::ostringstream out;
  (out << ... << internal::StrCatArg(args));
  return out.str();
}

// Appends the concatenation of args to *text.
template <typename... Args>
void StrAppend(std::string* text, const Args&... args) {
  text->append(StrCat(args...));
}

}  // namespace vpm

#define VPM_CONCAT_INNER_(a, b) a##b
#define VPM_CONCAT_(a, b) VPM_CONCAT_INNER_(a, b)

// Returns from the enclosing function when `expr` (a Status) is not OK.
#define RETURN_IF_ERROR(expr)                    \
  do {                                           \
    ::absl::Status vpm_status_ = (expr);         \
    if (!vpm_status_.ok()) return vpm_status_;   \
  } while (0)

// `ASSIGN_OR_RETURN(auto x, MakeX());` unwraps a Result or returns its error.
#define ASSIGN_OR_RETURN(lhs, expr) \
  ASSIGN_OR_RETURN_IMPL_(VPM_CONCAT_(vpm_result_, __LINE__), lhs, expr)
#define ASSIGN_OR_RETURN_IMPL_(tmp, lhs, expr) \
  auto tmp = (expr);                           \
  if (!tmp.ok()) return std::move(tmp).status(); \
  lhs = std::move(tmp).value()
