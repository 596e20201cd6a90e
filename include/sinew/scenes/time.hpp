// The "Time" section of a scene: quasi-static load steps (the default, and what every scene without
// the section does) or an implicit time integration with mass (Smith et al. 2018, Fig. 11):
//
//   <ParameterList name="Time">
//     <Parameter name="Integrator" type="string" value="implicit-midpoint"/>
//     <Parameter name="Frames" type="int" value="48"/>  <Parameter name="Frame rate" type="double" value="24"/>
//     <Parameter name="Substeps" type="int" value="10"/>
//   </ParameterList>
//
// A dynamic run takes Frames x Substeps time steps of h = 1 / (Frame rate x Substeps) seconds and
// writes fields once per frame (times Output/Every). Prescribed motions, bones and colliders follow
// the load fraction t / T over the run's T = Frames / Frame rate seconds, as they follow the load steps
// of a quasi-static run; body forces and gravity act in full from the start.
#pragma once

#include <sinew/core/errors.hpp>
#include <sinew/core/section.hpp>

#include <array>

namespace sinew {

struct TimeParameters {
  enum class Integrator { QuasiStatic, BackwardEuler, ImplicitMidpoint };
  Integrator integrator = Integrator::QuasiStatic;
  int frames = 0, substeps = 0;
  double frame_rate = 0.0, rayleigh_mass = 0.0, rayleigh_stiffness = 0.0;
  bool lumped = true;
  std::array<double, 3> initial_velocity{}, initial_spin{};

  bool dynamic() const { return integrator != Integrator::QuasiStatic; }
  int steps() const { return frames * substeps; }
  double end_time() const { return frames / frame_rate; }

  template <class V>
  void visit(V& v) {
    v.choice("Integrator", integrator, Integrator::QuasiStatic,
             Choices<Integrator>{{"quasi-static", Integrator::QuasiStatic},
                                 {"backward-euler", Integrator::BackwardEuler},
                                 {"implicit-midpoint", Integrator::ImplicitMidpoint}},
             "quasi-static load steps (Loading/Steps), or time steps with mass: backward-euler (first order, "
             "damps) or implicit-midpoint (second order, keeps energy and momenta)");
    v.entry("Frames", frames, 24, "frames of the dynamic run (output once per frame)", Range::closed(1, 1e7));
    v.entry("Frame rate", frame_rate, 24.0, "frames per second", Range::positive());
    v.entry("Substeps", substeps, 1, "time steps per frame", Range::closed(1, 1e5));
    v.choice("Mass", lumped, true, Choices<bool>{{"lumped", true}, {"consistent", false}},
             "mass matrix: lumped (the nodal masses, row sums) or consistent (int rho N_a N_b)");
    v.entry("Rayleigh mass", rayleigh_mass, 0.0, "damping alpha of D = alpha M + beta K, in 1/s", Range::non_negative());
    v.entry("Rayleigh stiffness", rayleigh_stiffness, 0.0,
            "damping beta of D = alpha M + beta K (K: the elastic Hessian at each step's start), in s",
            Range::non_negative());
    v.entry("Initial velocity", initial_velocity, {0.0, 0.0, 0.0}, "the body's velocity at t = 0");
    v.entry("Initial spin", initial_spin, {0.0, 0.0, 0.0},
            "an angular velocity (rad/s, about the rest centroid) added to the initial velocity");
  }
  template <class Context>
  void check(const Context& c) const {
    if (dynamic()) return;
    for (const char* e : {"Frames", "Frame rate", "Substeps", "Mass", "Rayleigh mass", "Rayleigh stiffness", "Initial velocity",
                          "Initial spin"})
      if (c.given(e)) c.fail("'" + std::string(e) + "' applies to a dynamic run (give 'Integrator' backward-euler or implicit-midpoint)");
  }
};

}  // namespace sinew
