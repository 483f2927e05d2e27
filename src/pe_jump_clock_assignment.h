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

#ifndef LMP_PE_JUMP_CLOCK_ASSIGNMENT_H
#define LMP_PE_JUMP_CLOCK_ASSIGNMENT_H

#include "pe_jump_atom_set.h"
#include "pointers.h"

#include <functional>
#include <string>

namespace LAMMPS_NS {
class Fix;
namespace PEJump {
  class AtomState;
  class InteractionSplit;

  // Which atoms of pe_jump/async are on which clock. The fine clock takes
  // the fast group and, with buffer layers, the slow partners of its
  // interactions layer by layer: then it is a group of its own, which the
  // fix creates and which moves with the atoms and into restart files.
  // After every list build the split interactions give the lists of the
  // atoms that are slow, and of those that move on fine steps (on the fine
  // clock, or slow in a fine interaction).

  class ClockAssignment : protected Pointers {
   public:
    // automatic: the fix adds atoms of its own choice to the fast group
    // the buffer: layers of slow partners, pairs closer than reach (0: the
    // pair style's cutoff)
    struct Buffer {
      int layers;
      double reach;
      bool operator!=(const Buffer &o) const { return (layers != o.layers) || (reach != o.reach); }
    };
    ClockAssignment(class LAMMPS *, Fix *, const char *fast_group, Buffer, bool fast_auto);

    void create_clock_group();    // after the fix exists (buffer layers only)
    // the group goes with the fix (unfix) unless something else uses it; not
    // when LAMMPS is torn down (the groups are gone first)
    void delete_clock_group() const;
    void find_groups();    // at init: the group bits, again (groups may be deleted)
    int clock_bit() const { return clockbit; }

    // at setup: (re)assign the buffer when the scheme starts, the layers
    // differ from those of the last run or restart file, or a static fast
    // group has atoms off the fine clock (redefined); true if done
    bool assign_buffer(bool started, InteractionSplit &);
    // a dynamic fast group, or atoms chosen by the fix (chosen[i] = 1,
    // owned atoms; nullptr: none): at the end of the coarse step that ends
    // at step node (steps fine steps), evaluate_at_node() evaluates the
    // group's criterion again after its updates (ghosts_at_node: the ghost
    // atoms are at the node already); at the coarse node, due()
    // tells if they changed (global), then follow() takes them (and the
    // buffer) on the fine clock; to_fine[i] (owned atoms) is 1 for an atom
    // that went to the fine clock, -1 to the coarse clock, 0 else. True if
    // any atom changed clock (global)
    void evaluate_at_node(bigint node, int steps, bool ghosts_at_node);
    bool due(const std::vector<int> *chosen, bigint node, int steps);
    bool follow(InteractionSplit &, std::vector<int> &to_fine, const std::vector<int> *chosen);
    bool follows_group() const { return dynamic || fast_auto; }
    bool dynamic_group() const { return dynamic; }
    // the fast group was dynamic when the restart file was written: a
    // warning at the next setup if it is static now (read_restart restores
    // groups without their dynamic definition)
    void restored_from_dynamic() { file_dynamic = true; }
    void warn_if_made_static();
    // the clock changes of a run (atoms, coarse nodes with a change, coarse
    // nodes looked at), reported in the log at its end, and counted anew
    void report(const char *style);
    // after a change: dh is what it added to the pseudo-energy (an atom
    // that changes clock restarts its jump: the pseudo-energy changes by
    // the jump energy it had less the one it starts with; global). A
    // warning, once, where the changes since the fix was defined added up
    // to more than a share of the group's kinetic energy (the larger of
    // that at the first change and kinetic(), collective, called only
    // then), an error where they added more than half of it
    void add_change_energy(double dh, const std::function<double()> &kinetic, const char *style);
    // true if the atoms on the fine clock changed since the last call (global)
    bool changed();

    // after a list build: the slow atoms, then those that move on fine
    // steps
    void find_slow(const InteractionSplit &);
    void find_moving(const InteractionSplit &);
    const int *slow() const { return slow_flag.data(); }
    // fast auto TOL: chosen[i] = 1 for the owned atoms of the fix group
    // that move too far over a coarse step for the coarse clock (jump: the
    // jumps [v]^n; nfine: K), see the .cpp
    void choose_fast(double tol, double coarse, int nfine, double **jump,
                     std::vector<int> &chosen) const;
    const int *moving() const { return moving_flag.data(); }
    AtomList moving_atoms;    // the atoms of the group that move on fine steps:
    AtomList fast_atoms;      // those on the fine clock
    AtomList slow_moving;     // and the slow ones in a fine interaction
    AtomList slow_held;       // the slow atoms in none (held during fine steps)
    AtomList slow_atoms;      // the atoms of the group on the coarse clock

    // restart: buffer layers and fine-clock atoms (number, ID hash) of
    // the last run (3 values in list), the fast group at the last
    // assignment (number, ID hash: 2 values in seen), which tells whether
    // a dynamic group changed when it is next evaluated, and the buffer's
    // reach
    void save(double *list, double *seen, double *reach) const;
    void restore(const double *list, const double *seen, const double *reach);

    // communication of the clock bit of the ghosts (forward) and of flags
    // set on ghosts (reverse): the fix passes its calls on
    bool reversing() const { return reverse_flags != nullptr; }
    void gather(std::vector<int> &);    // flags set on ghosts are set on their owners
    int pack_forward(int n, const int *list, double *buf) const;
    void unpack_forward(int n, int first, const double *buf);
    int pack_reverse(int n, int first, double *buf) const;
    void unpack_reverse(int n, const int *list, const double *buf);

   private:
    Fix *fix;
    std::string fast_group;
    Buffer buffer;
    int finebit, clockbit;
    bool dynamic;             // the fast group is dynamic
    bool fast_auto;           // the fix adds atoms to the fast group
    bool file_dynamic;        // the restart file's fast group was dynamic
    Buffer saved_buffer;      // of the last run (or restart file)
    double saved_clock[2];    // fine-clock atoms of the last run: number, ID hash
    double fast_seen[2];      // fast group at the last assignment: number, ID hash
    // the clock changes of the run (see report), and what the changes
    // since the fix was defined added to the pseudo-energy
    struct Changes {
      enum { ATOMS, CHANGED, NODES };
      bigint tally[3] = {0, 0, 0};
      double energy = 0.0;      // added to the pseudo-energy
      double kinetic = -1.0;    // of the group at the first change (-1: none yet)
      bool warned = false;
    } changes;
    std::vector<int> slow_flag;         // owned atoms: 1 if on the coarse clock
    std::vector<int> moving_flag;       // owned atoms: 1 if they move on fine steps
    std::vector<int> participant;       // owned and ghost atoms: in a fine interaction
    std::vector<int> *reverse_flags;    // reverse communication carries these flags
    bool own_group() const;
    void assign(InteractionSplit &, const std::vector<int> *chosen = nullptr);
    bool updated_in(bigint node, int steps) const;    // the group updated in the coarse step
    void fast_signature(double *, const std::vector<int> *chosen) const;
    bigint fast_off_clock() const;
  };

  // The classes of the atoms of pe_jump/async at coarse nodes, for output
  // (a field of the state table, the fix's per-atom vector): slow = on the
  // coarse clock; mixed = on the fine clock and sharing an interaction
  // with a slow atom; fast = the other fine-clock atoms; and their numbers

  class ClockClasses : protected Pointers {
   public:
    enum Class { OUTSIDE = -1, SLOW = 0, MIXED = 1, FAST = 2 };

    ClockClasses(class LAMMPS *, AtomState &);
    // with the ghosts at the node (collective)
    void label(const InteractionSplit &, ClockAssignment &, int groupbit);
    double count(int which) const { return counts[which]; }
    double *classes() const;

   private:
    AtomState &state;
    int class_field;                    // state field: the class
    std::vector<int> interface_flag;    // owned and ghost atoms: fine with a slow partner
    double counts[3];                   // global number of slow, mixed, fast atoms
  };

}    // namespace PEJump
}    // namespace LAMMPS_NS

#endif
