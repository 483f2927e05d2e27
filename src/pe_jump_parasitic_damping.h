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

#ifndef LMP_PE_JUMP_PARASITIC_DAMPING_H
#define LMP_PE_JUMP_PARASITIC_DAMPING_H

#include <cmath>
#include <limits>

namespace LAMMPS_NS {
class LAMMPS;
namespace PEJump {
  class AtomState;

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
  // Each atom is on one clock (fix pe_jump: one; fix pe_jump/async: the
  // fine and the coarse clock), whose steps it takes: the history of the
  // last step is kept per clock.

  class ParasiticDamping {
   public:
    static constexpr double AUTO_STEPS = 1000.0;
    static constexpr int NCLOCKS = 2;

    explicit ParasiticDamping(AtomState &);

    // damp_time < 0: auto, 0: off; dt the time step (of the coarse clock);
    // thermostats: fixes that thermostat the fix's atoms (forcing: one of
    // them adds forces). A run that may damp adds the state fields (before
    // the fix's maxexchange is set)
    void init(double damp_time, double dt, bool thermostats, bool forcing);
    void impulse_here() { impulse = 1; }
    int take_impulse();    // this rank's impulse flag, cleared
    // the flag reduced over the ranks; true if it turns damp auto on
    bool impulse_anywhere(bool seen);
    bool active() const { return on; }
    bool automatic_on() const { return damp_auto && on; }
    // a velocity change beside a thermostat is still to be noted (damp auto
    // starts damping there, and remembers it for the following runs)
    bool awaits_impulse() const { return damp_auto && thermostatted && !ever_changed; }
    double beta(double h) const;
    // damp auto damps in this run or from this step on: the log says so
    // (the damping changes the trajectory at second order in the time
    // step; damp 0 turns it off)
    void note(LAMMPS *, const char *style, bool from_now) const;

    // the state fields: h <F> and P of the last step per atom (nullptr
    // before a run that may damp), valid if the clock's last step was
    // damped (NaN for an atom created since, or that changed clock: forget())
    void allocate();    // (restart files that hold them)
    bool allocated() const { return impulse_field >= 0; }
    void forget(int i);

    // one step of a clock: the jumps of its atoms are pulled by
    // pull(); done() after it
    struct Step {
      double beta, h;
      double **impulse, **difference;
      bool history;
      // component k of atom i: favg the quadrature average of its force,
      // d = dtfm favg (dtfm = 2 h ftm2v / m), jmp [v]^n; on return jmp is
      // the value from which TwoStep::jump_component(d, ...) gives the
      // damped jump, and the step's values are kept
      void pull(int i, int k, double dtfm, double favg, double d, double &jmp) const
      {
        constexpr double NONE = std::numeric_limits<double>::quiet_NaN();
        // (impulses kept as h <F>: the last step's size may differ)
        const double dlast = history ? dtfm * impulse[i][k] / h : NONE;
        component(beta, d, dlast, history ? difference[i][k] : NONE, jmp, difference[i][k]);
        impulse[i][k] = h * favg;
      }
    };
    // nullptr if the clock's step of size h is not damped
    const Step *step(double h, int clock = 0);
    void done(int clock = 0) { history[clock] = last[clock].beta > 0.0; }
    void forget_history();    // the scheme restarts

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
    // step of each clock was damped (restart files)
    bool kicked() const { return ever_changed; }
    void set_kicked(bool flag) { ever_changed = flag; }
    bool has_history(int clock = 0) const { return history[clock]; }
    void set_history(bool flag, int clock = 0) { history[clock] = flag && allocated(); }

   private:
    AtomState &state;
    int impulse_field = -1, difference_field = -1;    // state fields, -1 until allocate()
    bool damp_auto = true, on = false, thermostatted = false;
    bool ever_changed = false;
    bool history[NCLOCKS] = {false, false};
    Step last[NCLOCKS] = {};
    double rate = 0.0;
    int impulse = 0;
  };
}    // namespace PEJump
}    // namespace LAMMPS_NS

#endif
