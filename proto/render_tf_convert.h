// RenderTransferFunction <-> v2::RenderTransferFunction, shared by the
// server (RenderSettings.render_tf) and the clients that read a file.
#pragma once

#include "server/io/render_transfer_function.h"
#include "vpm/v2/vpm.pb.h"

namespace vpm {

inline v2::RenderTransferFunction ToProto(const RenderTransferFunction& tf) {
  v2::RenderTransferFunction out;
  out.set_name(tf.name);
  for (const TfColorPoint& c : tf.colors) {
    v2::TfColorPoint* p = out.add_colors();
    p->set_value(c.value);
    p->set_r(c.rgb.r);
    p->set_g(c.rgb.g);
    p->set_b(c.rgb.b);
  }
  for (const TfOpacityPoint& o : tf.opacities) {
    v2::TfOpacityPoint* p = out.add_opacities();
    p->set_value(o.value);
    p->set_opacity_per_mm(o.opacity);
  }
  if (tf.lighting) {
    v2::TfLighting* l = out.mutable_lighting();
    l->set_shade(tf.lighting->shade);
    l->set_ambient(tf.lighting->ambient);
    l->set_diffuse(tf.lighting->diffuse);
    l->set_specular(tf.lighting->specular);
    l->set_specular_power(tf.lighting->specular_power);
  }
  return out;
}

// Not validated here: RenderPresetFromTf checks counts, order and ranges.
inline RenderTransferFunction FromProto(const v2::RenderTransferFunction& in) {
  RenderTransferFunction tf;
  tf.name = in.name();
  for (const v2::TfColorPoint& c : in.colors()) {
    tf.colors.push_back({c.value(), glm::dvec3(c.r(), c.g(), c.b())});
  }
  for (const v2::TfOpacityPoint& o : in.opacities()) {
    tf.opacities.push_back({o.value(), o.opacity_per_mm()});
  }
  if (in.has_lighting()) {
    const v2::TfLighting& l = in.lighting();
    tf.lighting = TfLighting{l.shade(), l.ambient(), l.diffuse(), l.specular(), l.specular_power()};
  }
  return tf;
}

}  // namespace vpm
