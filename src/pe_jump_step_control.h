/* -*- c++ -*- ----------------------------------------------------------
   LAMMPS - Large-scale Atomic/Molecular Massively Parallel Simulator
   https://www.lammps.org/, Sandia National Laboratories
   LAMMPS development team: developers@lammps.org

   Copyright (2003) Sandia Corporation.  Under the terms of Contract
   DE-AC04-94AL85000 with Sandia Corporation, the U.S. Government retains
   certain rights in this software.  This software is distributed under
   the GNU General Public License.

   See the README file in the top-level LAMMPS directory.
------------------------------------------------------------------------- */

#ifndef LMP_PE_JUMP_STEP_CONTROL_H
#define LMP_PE_JUMP_STEP_CONTROL_H

#include "pe_jump_node_sampler.h"

#include <cmath>

namespace LAMMPS_NS {
namespace PEJump {
  class AtomState;

  // The sizes of the steps: the adaptive step (adapt keyword) and the
  // compensation of step-size changes (compensate keyword). Both need the
  // quadrature-averaged forces of the last two steps, which are kept as
  // per-atom history in the fix's state table only if one of them is on.

  // Damping of the parasitic period-2 mode (damp keyword), which
  // thermostats drive (random forces, stochastic or repeated velocity
  // rescaling). With d_n = 2 h <F>/m the impulse of step n, a damped step
  // takes
  //   [v]^{n+1} = d_n - [v]^n + beta (3 P^n - P^{n-1})/4,
  //   P^n = [v]^n - (d_{n-1} + d_n)/4,
  // where P^n is the jump less the smooth jump at the node estimated from
  // the two steps beside it: (-1)^n c for the alternating jump, which is
  // multiplied by -(1 - beta) per step, and of order h^3 and even in time
  // on a smooth trajectory. The combination of two nodes puts the pull
  // half a step later, where the jump it changes acts: on a mode of
  // frequency omega the damping then changes the energy by beta O((h
  // omega)^6) per step, against beta (h omega)^2/8 when the jump was
  // pulled towards the step's own impulse d_n/2 (a negative drag that
  // heated thermostatted runs; doc/theory.md, section 3.0).
  // The impulses h <F> and the differences P of the last step are kept
  // per atom (two state fields, 48 bytes) from the first run that may damp.
  // damp auto: over AUTO_STEPS steps, beside a thermostat only (from the
  // start if it adds forces, else from the first step where a velocity
  // changed); a run that conserves energy (fix momentum, heat exchange,
  // external forces, ...) is left undamped.

  class ParasiticDamping {
   public:
    static constexpr double AUTO_STEPS = 1000.0;

    explicit ParasiticDamping(AtomState &);

    // damp_time < 0: auto, 0: off; dt the time step; thermostats: fixes
    // that thermostat this fix's atoms (forcing: one of them adds forces).
    // A run that may damp adds the state fields (before the fix's
    // maxexchange is set)
    void init(double damp_time, double dt, bool thermostats, bool forcing);
    void impulse_here() { impulse = 1; }
    int take_impulse();    // this rank's impulse flag, cleared
    // the flag reduced over the ranks; true if it turns damp auto on
    bool impulse_anywhere(bool seen);
    bool active() const { return on; }
    bool automatic_on() const { return automatic && on; }
    double beta(double h) const;

    // the state fields: h <F> and P of the last step per atom (nullptr
    // before a run that may damp), valid if has_history(): the last step
    // was damped (NaN for an atom created since); set_history(false) when
    // the scheme restarts. allocate(): add them (restart files that hold
    // them)
    double **impulses() const;
    double **differences() const;
    void allocate();
    bool allocated() const { return impulse_field >= 0; }

    // one component of a damped step: jmp holds [v]^n, d = 2 h <F>/m of
    // this step, dlast = 2 h <F>/m of the last step and plast its P (NaN
    // if there are none: 2 [v]^n and -P^n stand in). On return p holds P^n
    // and jmp the value from which TwoStep::jump_component(d, ...) gives
    // the jump of the damped step
    static void component(double beta, double d, double dlast, double plast, double &jmp, double &p)
    {
      if (!std::isfinite(dlast)) dlast = 2.0 * jmp;
      p = jmp - 0.25 * (dlast + d);
      if (!std::isfinite(plast)) plast = -p;
      jmp -= 0.25 * beta * (3.0 * p - plast);
    }

    // whether velocities were changed by another fix beside a thermostat
    // since the fix was defined: damp auto goes on damping in the next run
    // (split runs and restarts continue as one run); and whether the last
    // step was damped (the values it kept are valid)
    bool kicked() const { return ever_changed; }
    void set_kicked(bool flag) { ever_changed = flag; }
    bool has_history() const { return history; }
    void set_history(bool flag) { history = flag && allocated(); }

   private:
    AtomState &state;
    int impulse_field = -1, difference_field = -1;    // state fields, -1 until allocate()
    bool automatic = true, on = false, thermostatted = false;
    bool ever_changed = false, history = false;
    double rate = 0.0;
    int impulse = 0;
  };

  class StepControl : protected Pointers {
   public:
    // eps <= 0: no adaptive step
    StepControl(class LAMMPS *, AtomState &, double eps, double dtmin, double dtmax,
                bool compensate);

    bool adapts() const { return eps > 0.0; }
    bool keeps_history() const { return hist1 >= 0; }

    // at setup: the first step is taken with the timestep in range, and the
    // adaptive bound is relative to the pseudo-energy E0 at the start
    void start_run(const char *style, double pseudo_energy);

    // before the scheme starts with the kick [v]^0 = h F/m (f the forces at
    // q^0, pe the potential energy there): the first step is the time step
    // in range, or less if the kick's jump energy would exceed the share of
    // the bound that choose_next() aims at (a larger first step would be
    // cut at once, and the abrupt change excites the parasitic mode)
    void first_step(const char *style, const AtomSet &set, double **f, double pe);

    // the atoms of set at the start of a step of size h: add the
    // compensation of the step-size change to their jumps ([v] and
    // v^{n+1/2}), using scratch (3 per owned atom) as work space;
    // false if there was nothing to compensate
    bool compensate(double h, const AtomSet &set, double **vhalf, double **jump, double **scratch);

    // history slot for the average of the step now ending (the previous
    // one moves back); call once per step before writing into it
    double **next_history();
    void step_done(double h);    // the step of size h was taken

    // adapt: choose the next step from this step's averages favg
    void choose_next(const AtomSet &set, double **favg, double **jump);

    void set_timestep(double dt);

    // restart: the sizes of the last two steps
    void save(double *list) const;
    void load(const double *list);
    void forget() { hlast = hlast2 = 0.0; }

   private:
    AtomState &state;
    double eps, dtmin, dtmax;
    double energy_scale;    // |pseudo-energy| at the start of the run
    bool compensating;
    int hist1, hist2;        // state fields: averaged forces of the last two steps
    double hlast, hlast2;    // sizes of the last two steps, 0 if there are none
    double mass_of(int i) const;
    void bring_into_range(const char *style);    // the time step into [dtmin, dtmax]
    static double largest_step(const double *sum, double target, double hcap, double hlow);
  };

}    // namespace PEJump
}    // namespace LAMMPS_NS

#endif
