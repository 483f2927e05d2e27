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

#ifndef LMP_PE_JUMP_TWO_STEP_H
#define LMP_PE_JUMP_TWO_STEP_H

#include "pe_jump_node_sampler.h"
#include "pe_jump_parasitic_damping.h"

#include <functional>
#include <string>
#include <vector>

namespace LAMMPS_NS {
namespace PEJump {
  class AtomState;

  // The two-step scheme of a set of atoms: its per-atom state (fields of
  // the state table) and the updates of the velocities. Between its steps
  // an atom's atom->v is its node velocity v^n; inside them, its
  // free-flight velocity v^{n+1/2} = v^n + [v]^n/2. Fields: the jump [v]^n,
  // stored as 2 (v^{n+1/2} - v^n) of the rounded values so that v^n +
  // [v]^n/2 gives v^{n+1/2} back exactly; a fingerprint of the velocity the
  // scheme left in atom->v (a velocity found different was changed by
  // someone else); and (Lobatto rules) the sampled force at the start node.

  class TwoStep : protected Pointers {
   public:
    TwoStep(class LAMMPS *, AtomState &, bool start_nodes);

    // the per-atom state is valid (the scheme has started); set by a start,
    // cleared where the state no longer fits, told to every rank by
    // agree_on_started() at setup
    bool has_started() const { return started > 0; }
    void set_started(bool yes) { started = yes ? 1 : 0; }
    void restart_data_unfit() { started = -1; }    // (this rank, until setup)
    int fresh;    // 1 if atoms were created since the last setup (this rank)

    double **jump() const;
    double *vsig() const;
    double **fstart() const;    // nullptr without start nodes

    // refusals common to the fixes (run style, time step, torques), and
    // 1/m per atom type as the jump loops take it
    void init(const char *style);
    double inverse_mass_of(int i) const;

    // the ranks agree on started (restart data that does not fit, marked
    // -1, is told; so are atoms of the group deleted since the last run,
    // whose partners' jumps hold forces that are gone, atoms that joined
    // it, which have no jump, atoms moved by an energy minimization or a
    // command, whose jumps belong to the old positions, new masses or a new
    // time step, which the jumps do not fit, and a potential energy at the
    // positions of the last run's end that is not what it was then (a new
    // force field, a box changed), which they do not fit either: not
    // started; now: the energy tallied at setup);
    // non-finite velocities are refused
    // new_step_restarts: a time step changed since the last run restarts
    // the scheme too (unless the jumps are to be carried over)
    // (during a rerun not started: see reading_snapshots())
    void agree_on_started(const AtomSet &, const char *style, bool new_step_restarts,
                          const NodeSampler::Tallied &now);
    // true while the rerun command reads snapshots: it calls setup() for
    // each and integrates nothing, so every snapshot starts the scheme
    // afresh from its positions and velocities, without a word
    bool reading_snapshots() const;
    // the end of a run: the fingerprints of the velocities and the census
    // of the group (atoms, positions, masses, time step, the potential
    // energy tallied at the end), for the next run to compare
    void end_run(const AtomSet &, const NodeSampler::Tallied &energy);
    // "run N pre no" starts a run without setup(), so without the check
    // above: at the first step of such a run, an error if the state of
    // the last run no longer fits (changed velocities included, and
    // clocks_changed: the atoms on the fine clock of pe_jump/async); true
    // if LAMMPS was initialized in between (write_data, write_restart, ...
    // rebuild the ghost atoms, which the lists of the last build no longer
    // fit: the caller has them built)
    bool awaits_setup() const { return pending_setup; }
    bool check_run_without_setup(const char *style, const AtomSet &, bool clocks_changed);
    // an energy minimization moves the atoms (Fix::min_setup()): the state
    // belongs to the old positions, the next run restarts the scheme
    void atoms_minimized() { minimized = true; }
    // the census of the last run's end in a restart file written between
    // runs (NCENSUS values; none if written during a run), so that a run
    // after read_restart compares with it too
    static constexpr int NCENSUS = 11;
    void save_census(double *list) const;
    void load_census(const double *list);

    // [v]^0 = step(i) F/m: the initial kick (scale 1) or none (scale 0)
    void start(const AtomSet &, double **f, double scale, const std::function<double(int)> &step);

    // the steps of the atoms of set begin: v^n -> v^{n+1/2}
    void open(const AtomSet &, bool fingerprint) const;

    // one component of the update: with vh = v^{n+1/2} and jmp = [v]^n on
    // entry and dfavg = 2 h <F>/m, vh becomes the node velocity v^{n+1} and
    // jmp the jump [v]^{n+1}, stored as 2 (v^{n+3/2} - v^{n+1}) so that
    // v^{n+1} + jmp/2 gives v^{n+3/2} back; returns v^{n+3/2}
    static double jump_component(double dfavg, double &vh, double &jmp)
    {
      jmp = dfavg - jmp;
      const double vnew = vh + jmp;
      vh = vnew - 0.5 * jmp;
      jmp = 2.0 * (vnew - vh);
      return vnew;
    }

    // an atom (velocity v its v^{n+1/2}, jump jmp) jumps with the
    // quadrature sum favg of its forces over a step h, dtfm = 2 h ftm2v / m;
    // mag: the largest |v^{n+3/2}|^2 and |[v]^{n+1}|^2 so far; damp: the
    // step's parasitic damping (nullptr: none), i the atom's index
    static void jump_one(double dtfm, const double *favg, double *v, double *jmp, double *mag,
                         const ParasiticDamping::Step *damp = nullptr, int i = 0)
    {
      double vnew[3];
      for (int k = 0; k < 3; k++) {
        const double d = dtfm * favg[k];
        if (damp) damp->pull(i, k, dtfm, favg[k], d, jmp[k]);
        vnew[k] = jump_component(d, v[k], jmp[k]);
      }
      mag[0] = MAX(mag[0], vnew[0] * vnew[0] + vnew[1] * vnew[1] + vnew[2] * vnew[2]);
      mag[1] = MAX(mag[1], jmp[0] * jmp[0] + jmp[1] * jmp[1] + jmp[2] * jmp[2]);
    }
    const double *inverse_masses() const { return inverse_mass.data(); }    // per type

    // the atoms of set jump with favg over the step h and move on by rest
    // (from the primary node to the step end); fingerprints if asked; with
    // ahead >= 0 the next step begins and moves by ahead in the same pass,
    // with the same operations; damp: the step's parasitic damping
    struct Loop {
      double h, rest, ahead;
      bool fingerprint;
    };
    void jump_loop(const AtomSet &, double **favg, const Loop &, double *mag,
                   const ParasiticDamping::Step *damp = nullptr) const;

    void mark(int i) const;    // the fingerprint of atom->v[i]
    void mark_all(const AtomSet &) const;
    bool any_changed(const AtomSet &) const;    // on this rank

    // 0: the velocities are those the scheme left, 1: all were reversed
    // (then taken as the scheme's), 2: changed otherwise (global)
    int velocity_change(const AtomSet &, bool can_reverse);

    // pseudo-kinetic energy (1/2) sum m v^{n-1/2}.v^{n+1/2} and jump energy
    // (1/8) sum m |[v]^n|^2, computed once per time step (forget_energies()
    // after the state changed within one)
    const double *energies(const AtomSet &);
    void forget_energies() { cached_step = -1; }
    // the same two sums now, not cached (global)
    void energies_now(const AtomSet &, double *e) const;

   private:
    int started = 0;    // 1 valid, 0 not, -1 restart data did not fit (this rank)
    template <bool AHEAD, bool SIGN, bool DAMP>
    void jump_loop_as(const AtomSet &, double **favg, const Loop &, double *mag,
                      const ParasiticDamping::Step *damp) const;
    AtomState &state;
    int jump_field, vsig_field, fstart_field;
    std::vector<double> inverse_mass;
    bigint cached_step;
    double cached[2];
    // the atoms of the group (global number) and a weighted sum of their
    // unwrapped positions, sum_i w_i x_i with w_i in [1, 2) from a hash of
    // the ID, and its scale sum_i w_i |x_i|: moving atoms changes the sum,
    // wrapping them into a periodic box does not (beyond round-off)
    struct Census {
      bigint atoms;
      double moment[3];
      double scale;
      double mass;    // sum_i w_i m_i
      double dt;      // the time step
      NodeSampler::Tallied energy;
    };
    Census census(const AtomSet &, const NodeSampler::Tallied &) const;    // global
    Census at_end;         // at the end of the last run (atoms -1: none)
    bool minimized;        // an energy minimization since the last run
    bool pending_setup;    // a run ended, and no setup() since
    bool reinitialized;    // ... and init() was called since
    std::string changed_since_run(const Census &now, bool new_step_restarts) const;
  };

}    // namespace PEJump
}    // namespace LAMMPS_NS

#endif
