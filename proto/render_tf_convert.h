// RenderTransferFunction <-> v3::RenderTransferFunction, shared by the
// server (RenderSettings.render_tf) and the clients that read a file.
#pragma once

#include "server/io/render_transfer_function.h"
#include "vpm/v3/vpm.pb.h"

namespace vpm {

inline v3::RenderTransferFunction ToProto(const RenderTransferFunction& tf) {
  v3::RenderTransferFunction out;
  out.set_name(tf.name);
  for (const TfColorPoint& c : tf.colors) {
    v3::TfColorPoint* p = out.add_colors();
    p->set_value(c.value);
    p->set_r(c.rgb.r);
    p->set_g(c.rgb.g);
    p->set_b(c.rgb.b);
  }
  for (const TfOpacityPoint& o : tf.opacities) {
    v3::TfOpacityPoint* p = out.add_opacities();
    p->set_value(o.value);
    p->set_opacity_per_mm(o.opacity);
  }
  if (tf.lighting) {
    v3::TfLighting* l = out.mutable_lighting();
    l->set_shade(tf.lighting->shade);
    l->set_ambient(tf.lighting->ambient);
    l->set_diffuse(tf.lighting->diffuse);
    l->set_specular(tf.lighting->specular);
    l->set_specular_power(tf.lighting->specular_power);
  }
  return out;
}

// Not validated here: RenderPresetFromTf checks counts, order and ranges.
inline RenderTransferFunction FromProto(const v3::RenderTransferFunction& in) {
  RenderTransferFunction tf;
  tf.name = in.name();
  for (const v3::TfColorPoint& c : in.colors()) {
    tf.colors.push_back({c.value(), glm::dvec3(c.r(), c.g(), c.b())});
  }
  for (const v3::TfOpacityPoint& o : in.opacities()) {
    tf.opacities.push_back({o.value(), o.opacity_per_mm()});
  }
  if (in.has_lighting()) {
    const v3::TfLighting& l = in.lighting();
    tf.lighting = TfLighting{l.shade(), l.ambient(), l.diffuse(), l.specular(), l.specular_power()};
  }
  return tf;
}

}  // namespace vpm
