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
FixStyle(pe_jump,FixPEJump);
// clang-format on
#else

#ifndef LMP_FIX_PE_JUMP_H
#define LMP_FIX_PE_JUMP_H

#include "fix.h"

#include <string>
#include <vector>

namespace LAMMPS_NS {
namespace PEJump {
  struct AtomSet;
  class AtomState;
  class AutoQuadrature;
  struct Evaluations;
  class ForceSampler;
  struct FreeFlight;
  class NodeSampler;
  struct Options;
  class OtherFixes;
  class ParasiticDamping;
  class Quadrature;
  class StabilityGuard;
  class StepControl;
  class TwoStep;
  class WorkForces;
}    // namespace PEJump

class FixPEJump : public Fix {
 public:
  FixPEJump(class LAMMPS *, int, char **);
  ~FixPEJump() override;
  void post_constructor() override;

  int setmask() override;
  void init() override;
  void setup(int) override;
  void min_setup(int) override;
  void setup_pre_reverse(int, int) override;
  void post_neighbor() override;
  void initial_integrate(int) override;
  void pre_reverse(int, int) override;
  void final_integrate() override;
  void end_of_step() override;
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
  int pack_reverse_comm(int, int, double *) override;
  void unpack_reverse_comm(int, int *, double *) override;
  double memory_usage() override;

 private:
  using AtomList = std::vector<int>;

  // the parts: the keywords, quadrature rule (or the nested rules of
  // quadrature auto), force evaluation, node sampling, per-atom state, the
  // scheme's updates, step control and damping, the stability guard, what
  // other fixes do, and the work arrays
  PEJump::Options *opts;
  PEJump::Quadrature *rule;
  PEJump::AutoQuadrature *auto_quadrature;    // quadrature auto, or nullptr
  PEJump::ForceSampler *sampler;
  PEJump::NodeSampler *node_sampler;
  PEJump::AtomState *state;
  PEJump::TwoStep *two_step;
  PEJump::StepControl *step_control;
  PEJump::ParasiticDamping *damping;
  PEJump::StabilityGuard *guard;
  PEJump::OtherFixes *others;
  PEJump::WorkForces *work;    // SUM: the quadrature sum, SAMPLE: the sampled primary force

  int reinit_pending;            // redo the initial kick when all fix forces are in
  int opened_ahead;              // the last step began this one already
  int before_open;               // atom->v holds v^n while this step's nodes are checked
  int born;                      // atoms created in this step await their start (this rank)
  double advance_pending;        // free flight left for after this step's list build
  double h_step;                 // step size used in the current step
  double end_time;               // update->atime of the step; the node's during it
  PEJump::Evaluations *evals;    // force evaluations

  enum { SUM, SAMPLE };
  double **fsum() const;
  double **fsample() const;
  void grow_work();

  bool group_holds_all_local() const;    // every owned atom is in the group
  PEJump::AtomSet group_atoms() const;
  // forces not integrated by the rule (other fixes that add forces,
  // contributions left out by sample) act as impulses at the primary node,
  // where the sampled part is split off: by copying f before the reverse
  // communication if all contributions are sampled, else by a sampling
  bool split_primary() const;
  bool use_copy() const;
  void start_scheme(const char *, bool);
  void begin_step();
  void node_impulses();
  void open_steps();                 // v^n -> v^{n+1/2}
  bool open_while_moving() const;    // open_steps() and advance() may be one pass
  void open_and_advance(double t);
  void advance(double t);          // free flight to the primary node
  double advance_now(double t);    // free flight now (t, or to the step end)
  bool watch(int when) const;      // other fixes may change velocities then (OtherFixes hooks)
  PEJump::FreeFlight free_flight() const;    // the atoms' v^{n+1/2} inside the step
  void store_start_node();                   // Lobatto start-node forces at q^0
  void refresh_start_nodes();
  void start_new_atoms(double **fp, double rest);    // created inside this step
  void primary_sampled_force();
  void project_sampled();
  void quadrature_sum();
  void auto_quadrature_sum();
  void check_lists();    // neighbor lists valid for this step's nodes
  void check_excursion(double lo, double hi);
  std::string instability_advice() const;
  void tell_largest_jump() const;    // in the log, when the run stops as unstable
  void tally_at_node();
  void refuse_atoms_outside_include_group() const;
  void refuse_step_counters() const;
  void check_others_for_rule() const;
  double potential_now();
  void global_state(double *) const;

  // apply one(i) to the owned atoms of the group
  template <typename Function> void for_atoms(Function &&one) const;

  // the atoms of the group jump with the quadrature sums favg of their
  // forces over the step and move on by rest from the primary node to
  // q^{n+1}; mag: the largest |v^{n+3/2}|^2 and |[v]^{n+1}|^2 so far
  void finish_step(double **favg, double rest, double *mag);
  bool may_open_ahead() const;
};

}    // namespace LAMMPS_NS

#endif
#endif
