// For the benchmarks: what each inverted tet of a dragged model is made of.
#pragma once

#include <algorithm>
#include <cstdio>
#include <string>
#include <vector>

#include <glm/glm.hpp>

#include "server/fem/fem_model.h"
#include "server/volume/volume.h"

namespace vpm::bench {

// Per inverted tet: how many of its vertices are handles (H), fixed (X), on a
// box face (B), free but in a tet stiffer than the softest (S: a tet with a
// hard vertex, E_hard; such a vertex barely moves) or free (F), and its
// centroid's distance from the grab, mm.
inline void ExplainInvertedTets(const FemModel& model, const Volume& volume,
                                const glm::dvec3& grab) {
  const std::vector<glm::dvec3> x = model.Positions();
  const auto& handles = model.grab().handles;
  const glm::dvec3 extent = volume.geometry().extent_mm();
  // Per vertex: the largest shear modulus of its tets, N/mm^2.
  const auto& elements = model.solver().elements();
  std::vector<double> stiffest(x.size(), 0.0);
  double softest = 1e300;
  for (const auto& e : elements) {
    softest = std::min(softest, e.mu_n_per_mm2);
    for (int32_t v : e.vertices) stiffest[v] = std::max(stiffest[v], e.mu_n_per_mm2);
  }
  for (const auto& tet : model.tets()) {
    const glm::dvec3 a = x[tet[1]] - x[tet[0]], b = x[tet[2]] - x[tet[0]], c = x[tet[3]] - x[tet[0]];
    if (glm::dot(a, glm::cross(b, c)) > 0.0) continue;
    std::string kinds;
    glm::dvec3 centre(0.0);
    for (int32_t v : tet) {
      const glm::dvec3 p = model.rest_positions_mm()[v];
      centre += 0.25 * p;
      bool face = false;
      for (int i = 0; i < 3; ++i) face |= p[i] < 1e-6 * extent[i] || p[i] > extent[i] * (1 - 1e-6);
      kinds += std::binary_search(handles.begin(), handles.end(), v) ? 'H'
               : !model.deformable()[v]                              ? 'X'
               : face                                                ? 'B'
               : stiffest[v] > softest                               ? 'S'
                                                                     : 'F';
    }
    // The fixed vertex nearest the tet (rest positions): a free vertex
    // squeezed between handles and a fixed one has no room to give.
    double nearest_fixed = 1e300;
    glm::dvec3 fixed_at(0.0);
    for (size_t v = 0; v < x.size(); ++v) {
      if (model.deformable()[v]) continue;
      const double d = glm::distance(model.rest_positions_mm()[v], centre);
      if (d < nearest_fixed) nearest_fixed = d, fixed_at = model.rest_positions_mm()[v] - grab;
    }
    std::printf("  inverted %s at %.1f mm from the grab; nearest fixed vertex %.1f mm from it, "
                "at grab + (%.1f, %.1f, %.1f) mm\n",
                kinds.c_str(), glm::distance(centre, grab), nearest_fixed, fixed_at.x,
                fixed_at.y, fixed_at.z);
  }
  // The free vertices held by hard tets near the grab (within 1.5 times the
  // farthest inverted tet's distance): the tissue between them and the
  // handles takes all the shear.
  double reach = 0.0;
  for (const auto& tet : model.tets()) {
    const glm::dvec3 a = x[tet[1]] - x[tet[0]], b = x[tet[2]] - x[tet[0]], c = x[tet[3]] - x[tet[0]];
    if (glm::dot(a, glm::cross(b, c)) > 0.0) continue;
    glm::dvec3 centre(0.0);
    for (int32_t v : tet) centre += 0.25 * model.rest_positions_mm()[v];
    reach = std::max(reach, 1.5 * glm::distance(centre, grab));
  }
  int held = 0;
  double held_moved = 0.0;
  for (size_t v = 0; v < x.size(); ++v) {
    if (!model.deformable()[v] || !(stiffest[v] > softest)) continue;
    if (glm::distance(model.rest_positions_mm()[v], grab) > reach) continue;
    ++held;
    held_moved = std::max(held_moved, glm::distance(x[v], model.rest_positions_mm()[v]));
  }
  std::printf("  %d free vertices in hard tets within %.1f mm of the grab (S), moved at most "
              "%.2f mm\n", held, reach, held_moved);
}

}  // namespace vpm::bench
