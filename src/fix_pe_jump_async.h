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

#ifdef FIX_CLASS
// clang-format off
FixStyle(pe_jump/async,FixPEJumpAsync);
// clang-format on
#else

#ifndef LMP_FIX_PE_JUMP_ASYNC_H
#define LMP_FIX_PE_JUMP_ASYNC_H

#include "fix.h"

#include <string>
#include <vector>

namespace LAMMPS_NS {
namespace PEJump {
  class TwoClocks;
  struct AtomSet;
  class AtomState;
  class ClockAssignment;
  class ClockClasses;
  struct Evaluations;
  class ForceSampler;
  struct FreeFlight;
  class GrowthWatch;
  class InteractionSplit;
  class MovingGhosts;
  class NodeSampler;
  struct Options;
  class OtherFixes;
  class ParasiticDamping;
  class Quadrature;
  class SplitTally;
  class StabilityGuard;
  class TwoStep;
  class WorkForces;
}    // namespace PEJump

class FixPEJumpAsync : public Fix {
 public:
  FixPEJumpAsync(class LAMMPS *, int, char **);
  ~FixPEJumpAsync() override;
  void post_constructor() override;

  int setmask() override;
  void init() override;
  void setup(int) override;
  void min_setup(int) override;
  void setup_post_neighbor() override;
  void setup_pre_reverse(int, int) override;
  void initial_integrate(int) override;
  void post_neighbor() override;
  void pre_force(int) override;
  void pre_reverse(int, int) override;
  void final_integrate() override;
  void post_run() override;

  double compute_scalar() override;
  double compute_vector(int) override;

  void grow_arrays(int) override;
  void copy_arrays(int, int, int) override;
  void set_arrays(int) override;
  int pack_exchange(int, double *) override;
  int unpack_exchange(int, double *) override;
  void write_restart(FILE *) override;
  void restart(char *) override;
  int pack_restart(int, double *) override;
  void unpack_restart(int, int) override;
  int size_restart(int) override;
  int maxsize_restart() override;
  int pack_forward_comm(int, int *, double *, int, int *) override;
  void unpack_forward_comm(int, int, double *) override;
  int pack_reverse_comm(int, int, double *) override;
  void unpack_reverse_comm(int, int *, double *) override;
  double memory_usage() override;

 private:
  using AtomList = std::vector<int>;

  // the parts: the keywords, the quadrature rule, force evaluation, node
  // sampling, per-atom state, the scheme's updates, the stability guard,
  // the damping of the parasitic mode, the fine steps' ghost
  // communication, what other fixes do, the split of the interactions, where the clocks
  // are inside the coarse step, which atom is on which clock, and the
  // work arrays
  PEJump::Options *opts;
  PEJump::Quadrature *rule;
  PEJump::ForceSampler *sampler;
  PEJump::NodeSampler *node_sampler;
  PEJump::AtomState *state;
  PEJump::TwoStep *two_step;
  PEJump::StabilityGuard *guard;
  PEJump::GrowthWatch *growth;    // slow growth of the jumps (a warning)
  PEJump::ParasiticDamping *damping;
  PEJump::MovingGhosts *ghosts;
  PEJump::OtherFixes *others;
  PEJump::SplitTally *tally;
  PEJump::InteractionSplit *split;
  PEJump::TwoClocks *clocks;
  PEJump::ClockAssignment *clock_assignment;
  PEJump::ClockClasses *classes;
  PEJump::WorkForces *work;

  // the per-atom state fields (AtomState): facc the sum of the fine forces
  // on a slow atom over the fine steps done in this coarse step (force x
  // time); fstart_coarse the coarse interactions' force at the coarse start
  // node (rules that reuse it, else -1); end_impulse the impulse at the
  // coarse end node that the next coarse step begins with (Lobatto rules,
  // else -1); half_impulse half the impulse of the other fixes' forces in
  // the last coarse step (the other rules, else -1: CentreVelocity);
  // fcoarse the coarse quadrature sum of a slow atom's coarse interactions
  struct {
    int facc, fstart_coarse, end_impulse, half_impulse, fcoarse;
  } field;
  // the coarse step in progress
  struct StepNow {
    double end_time = 0.0;        // update->atime of its end
    bool lists_forced = false;    // LAMMPS builds the lists in it whatever the atoms do
    double speed2 = 0.0;          // largest |v|^2 of the moving atoms
    double change = 0.0;          // largest velocity change of an atom over a fine step
  } step_now;

  PEJump::Evaluations *evals;    // force evaluations
  int changes_seen;              // another fix changed a velocity (this rank)
  bool reverse_copy;             // the reverse communication sums COPY
  bigint builds_inside;          // list builds inside coarse steps (this run)
  bool impulse_at_start;         // the end impulse field holds -F(q^0) until the first step
  bool impulse_pending;          // the end impulse field may hold an impulse (else it is 0)

  // SUM: fine quadrature sum, COPY: the coarse interactions' forces at the
  // primary coarse node (owned and ghost atoms) apart from those that
  // other fixes add, VFREE: the free-flight velocities while the other
  // fixes see others there (CentreVelocity)
  enum { SUM, COPY, VFREE };
  bool shows_centre_velocities() const;
  void grow_work();
  int needed_work() const;
  PEJump::AtomSet group_atoms(const AtomList *only = nullptr) const;
  bool watch(int when) const;    // other fixes may change velocities then (OtherFixes hooks)
  PEJump::FreeFlight free_flight() const;    // inside the coarse step: all atoms in their steps

  void refuse_keywords() const;
  void refuse_unsplittable() const;
  void refuse_pair_misfit() const;    // at setup: the split's probes of the pair style
  void refuse_other_fixes() const;
  void check_clocks();
  void sort_by_clock();    // after list builds and clock changes
  void start_scheme(const char *, bool);
  void change_clocks();    // a dynamic fast group or fast auto, at coarse nodes
  double fine_forces_at_node(double **fnode, const std::vector<int> *to_fine);
  void restart_jumps(const std::vector<int> &to_fine, double **f);
  void store_start_node();    // Lobatto start nodes at q^0 (fine, and coarse for slow atoms)
  void continue_scheme();
  void node_impulses();
  void refuse_velocity_changes();    // an error if another fix changed a velocity

  // one coarse step: the fine steps up to the primary coarse node, where
  // the MD step evaluates the coarse interactions, then the rest
  void begin_coarse_step();
  void fine_steps_until(double nodes_in_fine_steps);
  void fine_step(bool next_ahead);       // ... and the next one whole here: begin it ahead
  bool check_fine_nodes(double into);    // true if the lists must be built first
  void build_lists_now();
  void lists_fit_step_end();
  void move_moving(double dt);
  void hold_until(double t);    // the slow atoms outside fine interactions move to t
  void fine_quadrature_sum(bool walked);
  bool walks_inner_nodes() const;
  double walk_inner_nodes(double into);
  void finish_fine_step(double **favg, double ahead, double *mag);
  void keep_coarse_primary(double **fcoarse);
  double **coarse_forces_apart();
  void end_impulse_first_half();
  void coarse_quadrature_sum();
  bool primary_is_last_node() const;
  void add_fine_forces_at_end();
  void slow_jumps(double *mag, double **fprimary);
  template <bool PRIMARY> void slow_jumps_as(double *mag, double **fcoarse);
  std::string instability_advice() const;
  void watch_growth();
  void slow_magnitudes();
  double node_cost() const;
  void show_classes();    // vector_atom follows the state table
  void log_steps() const;
};

}    // namespace LAMMPS_NS

#endif
#endif
