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

#include "pe_jump_atom_set.h"
#include "pointers.h"

#include <cmath>

namespace LAMMPS_NS {
namespace PEJump {
  class AtomState;

  // The sizes of the steps: the adaptive step (adapt keyword) and the
  // compensation of step-size changes (compensate keyword). Both need the
  // quadrature-averaged forces of the last two steps, which are kept as
  // per-atom history in the fix's state table only if one of them is on.

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
