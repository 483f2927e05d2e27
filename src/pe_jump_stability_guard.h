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

#ifndef LMP_PE_JUMP_STABILITY_GUARD_H
#define LMP_PE_JUMP_STABILITY_GUARD_H

#include "pe_jump_atom_set.h"
#include "pe_jump_reach_bound.h"
#include "pointers.h"

#include <cmath>
#include <functional>
#include <string>

namespace LAMMPS_NS {
namespace PEJump {
  class ParasiticDamping;
  class Quadrature;

  // Before the atoms move in a step: the nodes where forces will be taken
  // lie on the segments x + t v^{n+1/2}, t in [lo, hi]. The guard measures
  // how far they are from the positions of the last neighbor list build
  // (a rebuild is due beyond half the skin) and tells a time step beyond
  // the stability limit by the growth of the momentum jumps.
  //
  // Measures, per rank then reduced with MAX: excursion^2, step length^2,
  // jump displacement^2 (h |[v]|)^2, |[v]|^2, |v^{n+1/2}|^2.

  class StabilityGuard : protected Pointers {
   public:
    static constexpr int NMEASURES = 5;
    static constexpr double BLOWUP = 1.0e300;    // stands for a non-finite value

    explicit StabilityGuard(class LAMMPS *);

    // free_flight_only: nothing but the fix moves the atoms or changes
    // their velocities (other fixes, a changing box), see excursion_since()
    void start_run(bool free_flight_only);
    // the largest |v^{n+1/2}|^2 and |[v]|^2 after a step (speeds of the next)
    void set_stats(double vv, double jj);
    void forget_stats()
    {
      valid = false;
      reach.forget();
    }
    bool has_stats() const { return valid; }
    // the same for the atoms on a coarse clock (pe_jump/async), whose
    // velocities change only at coarse nodes; joined into local[1..4] for
    // the coarse step
    void set_slow_stats(double vv, double jj);
    void join_slow_stats(double coarse, double *local) const;

    // the measures of the atoms of set from their state, for steps of size
    // h: nodes at t in [lo, hi] from where the atoms are
    struct Nodes {
      double h, lo, hi;
    };
    void measure(const AtomSet &, const FreeFlight &, double **jump, double **xhold, const Nodes &,
                 double *local) const;
    // the measures of a step: where the last step left stats, speeds and
    // jumps from them and distances (excursion_since()) only if xhold,
    // else measure()
    void step_measures(const AtomSet &, const FreeFlight &, double **jump, double **xhold,
                       const Nodes &, double *local);

    // the same for one atom at x (xhold its build position or null) moving
    // with vhalf
    static void measure_one(const double *x, const double *xhold, const double *vhalf,
                            const double *jump, const Nodes &at, double *local)
    {
      double vv = 0.0, jj = 0.0, d[2] = {0.0, 0.0};
      for (int k = 0; k < 3; k++) {
        vv += vhalf[k] * vhalf[k];
        jj += jump[k] * jump[k];
        if (xhold) {
          const double a = x[k] - xhold[k];
          const double ends[2] = {a + at.lo * vhalf[k], a + at.hi * vhalf[k]};
          for (int e = 0; e < 2; e++) d[e] += ends[e] * ends[e];
        }
      }
      double step = at.h * at.h * vv, jmp = at.h * at.h * jj;
      if (!std::isfinite(step) || !std::isfinite(jmp)) step = jmp = vv = jj = BLOWUP;
      local[0] = MAX(local[0], MAX(d[0], d[1]));
      local[1] = MAX(local[1], step);
      local[2] = MAX(local[2], jmp);
      local[3] = MAX(local[3], jj);
      local[4] = MAX(local[4], vv);
    }

    // true if LAMMPS' own check of the step ends covers the nodes x + t v,
    // t in [lo, hi], of a step h whose nodes include both ends
    bool ends_checked(const Quadrature &, double lo, double hi, double h) const;

    // true if the Verlet loop rebuilds the lists in this step whatever the
    // atoms' positions (neigh_modify check no: every N steps, or a restart
    // file or a fix asks for it); with a distance check it is up to LAMMPS
    bool rebuild_forced() const;
    // an error for a zero neighbor skin unless every force evaluation is at
    // the positions where LAMMPS builds the lists (what, for the message)
    void refuse_zero_skin(const char *style, bool evaluations_at_builds,
                          const std::string &what) const;

    // largest excursion^2 of the nodes x + t v, t = lo and hi, from xhold
    double excursion(const AtomSet &, const FreeFlight &, double **xhold, double lo,
                     double hi) const;
    // Bounds on how far atoms are from their build positions (ReachBound),
    // kept where the fix alone moves the atoms and sets their velocities
    // (start_run()); a list build, forgotten stats or a new run measure
    // again. step(h) as every step begins, before its measures: the atoms
    // move by at most h times the largest speed of the stats in it.
    void step(double h);
    // excursion() of a set that is measured at every step (forget_reach()
    // where a step measures nothing), or 0 where its nodes cannot be beyond
    // half the skin: the verdict is that of excursion()
    double excursion_since(const AtomSet &, const FreeFlight &, double **xhold, double lo,
                           double hi);
    void forget_reach() { reach.forget(); }

    enum Verdict { FINE, REBUILD, UNSTABLE, TOO_FAR };
    Verdict judge(const double *global);    // the reduced measures
    double growth() const { return last_growth; }

    // the end of a step's check, in both fixes: reduce the local measures
    // over the ranks, with damping's flag of a velocity changed by another
    // fix (damp auto may start damping there: the log says so), and act
    // on the verdict: an error if the scheme is unstable or atoms move too
    // far; true if a list rebuild is due. energies() gives the
    // pseudo-kinetic and the jump energy of the group (TwoStep::energies,
    // collective), advice() the hint of the error
    bool conclude(const char *style, const double *local, ParasiticDamping &damping,
                  const std::function<const double *()> &energies,
                  const std::function<std::string()> &advice);

   private:
    // local[1..4] (the layout of measure()) from the stats, for steps of size h
    void measures_from_stats(double h, double *local) const;
    double stats[2], slow[2];
    bool valid;
    double jump_ref;    // largest |[v]|^2 or |v|^2 of the first steps of the run
    double last_growth;
    int hinted;          // steps in a row with grown jumps that move atoms far
    bool trusted;        // only the fix moves the atoms, with the speeds of the stats
    ReachBound reach;    // of the nodes of the atoms measured by excursion_since()

    bool free_flight_only() const { return trusted && valid; }
    double travel(double t, double speed2, int moves) const;
    double clear() const;
  };

}    // namespace PEJump
}    // namespace LAMMPS_NS

#endif
