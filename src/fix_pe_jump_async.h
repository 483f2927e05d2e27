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

#include "fix_pe_jump.h"

#include <string>

#include <vector>

namespace LAMMPS_NS {
namespace PEJump {
  class AsyncClocks;
  class InteractionSplit;
}    // namespace PEJump

class FixPEJumpAsync : public FixPEJump {
 public:
  FixPEJumpAsync(class LAMMPS *, int, char **);
  ~FixPEJumpAsync() override;
  void post_constructor() override;

  int setmask() override;
  void init() override;
  void setup(int) override;
  void setup_post_neighbor() override;
  void post_neighbor() override;
  void pre_force(int) override;
  void pre_reverse(int, int) override;
  void final_integrate() override;

  double compute_vector(int) override;

  void grow_arrays(int) override;
  void copy_arrays(int, int, int) override;
  void set_arrays(int) override;
  int unpack_exchange(int, double *) override;
  void unpack_restart(int, int) override;
  void write_restart(FILE *) override;
  void restart(char *) override;
  int pack_forward_comm(int, int *, double *, int, int *) override;
  void unpack_forward_comm(int, int, double *) override;
  int pack_reverse_comm(int, int, double *) override;
  void unpack_reverse_comm(int, int *, double *) override;
  double memory_usage() override;

 protected:
  enum Class { OUTSIDE = -1, SLOW = 0, MIXED = 1, FAST = 2 };

  int finebit;                        // group bit of the fast group
  std::string fast_group;             // its name, looked up again in init()
  int clockbit;                       // group bit of the atoms on the fine clock
  double counts[3];                   // global number of slow, mixed, fast atoms
  double stats_slow[2];               // largest |v|^2, |[v]|^2 of the local slow atoms
  std::vector<int> *reverse_flags;    // reverse communication carries these flags
  bigint split_calls;                 // neighbor->ncalls when the interactions were split
  bigint topology_at_setup;           // bonds, angles, ... when the run started
  int changes_seen;                   // another fix changed a velocity (this rank)
  int saved_buffer;                   // buffer layers of the last run (or restart file)
  double saved_clock[2];              // fine-clock atoms of the last run: number, sum of IDs

  PEJump::InteractionSplit *split;
  PEJump::AsyncClocks *clocks;

  // per-atom state fields: the quadrature sum of the forces on slow atoms
  // over the fine steps done in this coarse step (force x time), (Lobatto
  // rules) the slow-interaction force at the coarse start node, and the
  // class (the clocks add the time of each atom's position)
  int FACC, FSTART_COARSE, KLASS;

  double **fcoarse;    // work: coarse quadrature sum of the slow interactions
  int nmax_coarse;
  std::vector<int> slow;              // owned atoms: 1 if on the coarse clock
  std::vector<int> interface_flag;    // owned and ghost atoms: fine with a slow partner
  std::vector<int> moving;            // owned atoms: 1 if they move on fine steps
  std::vector<int> participant;       // owned and ghost atoms: in a fine interaction
  AtomList moving_atoms;              // the atoms of the group that move on fine steps:
  AtomList fast_atoms;                // those on the fine clock
  AtomList slow_moving;               // and the slow ones in a fine interaction
  AtomList slow_atoms;                // the atoms of the group on the coarse clock
  std::vector<double> lag;            // work: time by which an atom lags behind

  void start_scheme(const char *, bool) override;
  void node_impulses() override;
  double kick_step(int) const override;
  void store_start_node() override;
  double node_cost() override;
  void check_lists() override;
  void advance(double) override;
  std::string instability_advice() const override;
  bool can_reverse() const override;

  bigint topology_count() const;
  void refuse_unsplittable() const;
  void refuse_other_fixes() const;
  void find_groups();
  void note_velocity_changes(const AtomList *);
  void open_steps() override;
  PEJump::FreeFlight free_flight() const override;
  bool open_while_moving() const override;
  void check_clocks();
  void assign_buffer();
  void find_slow();
  void find_moving();
  void slow_magnitudes();
  void show_classes();    // vector_atom follows the state table
  void catch_up_all();    // the atoms that sit out fine steps catch up
  void coarse_quadrature_sum(double coarse_step);
  void reach_coarse_node(double **favg, double mag[2][2]);
  void continue_fine_step(double **favg, double *mag);
  void label_classes();
  void gather_flags(std::vector<int> &);
};

}    // namespace LAMMPS_NS

#endif
#endif
