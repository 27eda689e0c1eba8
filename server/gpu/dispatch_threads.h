// How many threads a CPU Vulkan device splits one dispatch among. lavapipe
// (llvmpipe's compute thread pool) hands each of its threads one contiguous
// run of a dispatch's workgroups, in the order x, then y, then z; it does
// not balance them as they finish. A kernel whose cost varies over its grid
// (the ray caster: rays through the body against rays through air) lays its
// workgroups out so that every run is a sample of the whole grid
// (shaders/raycast_body.glsl, band_row); docs/LAVAPIPE.md, "How a dispatch
// is split".
#ifndef VPM_SERVER_GPU_DISPATCH_THREADS_H_
#define VPM_SERVER_GPU_DISPATCH_THREADS_H_

#include <cstdint>

namespace vpm::gpu {

// lavapipe's thread count as it sets it: LP_NUM_THREADS where set, else
// the online CPUs, at most 32 (LP_MAX_THREADS); at least 1 (with 0 threads
// it runs the dispatch on the submitting thread, in order). 1 for a GPU,
// whose scheduler hands workgroups out as its units free up.
uint32_t DispatchThreads(bool cpu_device);

}  // namespace vpm::gpu

#endif  // VPM_SERVER_GPU_DISPATCH_THREADS_H_
