// TF(value) of docs/ALGORITHM.md section 1: piecewise linear through sorted
// control points, clamped outside. Expects the uniform block
// `TransferFunctionBlock { vec4 points[VPM_MAX_TF_POINTS]; ivec4 count; } u_tf`.
//
// Branch-free: the first cost plus, for each segment, its slope times the
// part of [x_i, x_i+1] below the value. Every invocation runs the same
// uniform loop, which keeps lavapipe's SIMD lanes together.
#ifndef VPM_TRANSFER_FUNCTION_GLSL
#define VPM_TRANSFER_FUNCTION_GLSL

// Specialization constant 0: the point count the pipeline was built for, so
// that the loop unrolls with constant uniform offsets (3x faster per voxel on
// lavapipe); 0 (the default) reads u_tf.count at run time.
layout(constant_id = 0) const int VPM_TF_POINTS = 0;

float transfer_cost(float value) {
  int n = VPM_TF_POINTS > 0 ? VPM_TF_POINTS : u_tf.count.x;
  float cost = u_tf.points[0].y;
  for (int i = 1; i < n; ++i) {
    vec2 lo = u_tf.points[i - 1].xy;
    vec3 hi = u_tf.points[i].xyz;  // z: the segment's slope, from the host
    // A zero-width segment is a step, taken at value >= x (right-continuous,
    // as TransferFunction::Evaluate).
    cost += hi.x > lo.x ? (clamp(value, lo.x, hi.x) - lo.x) * hi.z
                        : (value >= hi.x ? hi.y - lo.y : 0.0);
  }
  return cost;
}

#endif
