// Unguessable identifiers: bytes from the kernel's CSPRNG (getrandom(2)),
// written as lower-case hex.
#pragma once

#include <cstddef>
#include <string>

namespace vpm {

// 2 * `bytes` hex digits; RandomHex(16) is 128 bits. Blocks only before the
// kernel's pool is first seeded (early boot), never after.
std::string RandomHex(size_t bytes);

}  // namespace vpm
