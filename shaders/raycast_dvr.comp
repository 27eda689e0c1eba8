#version 450
#extension GL_GOOGLE_include_directive : require
// Ray casting: DVR, no backward map (identity), volume from a uniform texel buffer.
// The body and the list of variants: raycast_body.glsl.
#include "raycast_body.glsl"
