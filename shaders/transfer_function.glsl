// TF(value) of ALGORITHM.md section 1: piecewise linear through sorted
// control points, clamped outside. Expects the uniform block
// `TransferFunctionBlock { vec4 points[VPM_MAX_TF_POINTS]; ivec4 count; } u_tf`.
#ifndef VPM_TRANSFER_FUNCTION_GLSL
#define VPM_TRANSFER_FUNCTION_GLSL

float transfer_cost(float value) {
  int n = u_tf.count.x;
  if (value <= u_tf.points[0].x) return u_tf.points[0].y;
  if (value >= u_tf.points[n - 1].x) return u_tf.points[n - 1].y;
  for (int i = 1; i < n; ++i) {
    vec2 hi = u_tf.points[i].xy;
    if (value < hi.x) {
      vec2 lo = u_tf.points[i - 1].xy;
      return lo.y + (value - lo.x) / (hi.x - lo.x) * (hi.y - lo.y);
    }
  }
  return u_tf.points[n - 1].y;
}

#endif
