#version 450
#extension GL_GOOGLE_include_directive : require
// Ray casting: MIP, no backward map (identity), volume from a sampler3D.
// The body and the list of variants: raycast_body.glsl.
#define VPM_RAYCAST_MIP
#define VPM_RAYCAST_SAMPLED
#include "raycast_body.glsl"
