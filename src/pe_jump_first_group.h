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

#ifndef LMP_PE_JUMP_FIRST_GROUP_H
#define LMP_PE_JUMP_FIRST_GROUP_H

#include "pe_jump_force_sampler.h"
#include "pointers.h"

#include <vector>

namespace LAMMPS_NS {
namespace PEJump {

  // The opt-in "atom_modify first G" + "neigh_modify include G" for fix
  // pe_jump/async: LAMMPS stores the owned atoms of group G first (nfirst of
  // them) and then, every step, clears the forces of those nfirst atoms (and
  // of the ghosts) only, checks the distances moved since the last list
  // build of those only, and builds pair lists of pairs inside G only (the
  // topology lists keep every bond, angle, ...). With G = the atoms on the
  // fine clock, LAMMPS' own per-step work then scales with the fine subset.
  //
  // This part makes up for what LAMMPS then leaves out for the atoms after
  // nfirst, so that the trajectory is the one without the opt-in:
  //  - forces: the partners of fine interactions after nfirst are cleared
  //    every step; all atoms after nfirst once after anything wrote forces
  //    on them (a complete evaluation at setup or for energy/virial tallies,
  //    a list build, which moves atoms between slots);
  //  - distances: the atoms after nfirst that moved are checked as LAMMPS
  //    would (same test, same steps), and a rebuild is asked for; their
  //    positions at the build are kept in the rows of the neighbor class'
  //    xhold that LAMMPS leaves unused, for the fix's own node checks.

  class FirstGroup : protected Pointers {
   public:
    explicit FirstGroup(class LAMMPS *);

    // true if neigh_modify include restricts LAMMPS to the first nfirst atoms
    bool active() const;

    // what the opt-in cannot work with (collective): a pair style (pairs
    // with atoms outside G are not in the lists), a dynamic group G, a
    // changing box (LAMMPS' check then shrinks the trigger distance)
    void refuse_unsupported(const char *style) const;

    // fix pe_jump moves every atom of its group every step: all of them
    // must be in G (collective)
    void require_all(int groupbit, const char *style) const;

    // every atom of the fix group on the fine clock must be in G (collective)
    void require_fine_clock(int groupbit, int clockbit, bool buffer) const;

    // right after a list build, before any atom moves: keep the positions of
    // the atoms after nfirst as reference, and their forces are stale (if the
    // lists were not built at this step, a rebuild is asked for)
    void keep_build_positions();
    // the atoms after nfirst: those in a fine interaction (participant[i],
    // owned atoms) and those of the fix group that move on fine steps
    // (moving[i]); after the classes of the atoms were found
    void find_partners(const int *participant, const int *moving, int groupbit);

    // forces of the atoms after nfirst: all of them at setup, before the
    // complete evaluation (which leaves them stale for the first step); the
    // fine partners every step before the force styles, all of them once
    // after forces_written()
    void clear_before_setup();
    void clear_stale_forces();
    void forces_written() { stale_all = true; }

    // the owned atoms that the fine interactions act on: the first nfirst
    // and the partners after them (nullptr without the opt-in: all atoms)
    const ForceSampler::Touched *fine_atoms() const { return active() ? &fine : nullptr; }

    // the atoms of the fix group that sit out fine steps moved (catch-up)
    void held_atoms_moved() { held_moved = true; }
    // after the atoms moved to this step's primary node (all atoms of the
    // fix group if every_atom_moved): true on every rank if LAMMPS' distance
    // check would ask for a rebuild for an atom after nfirst, or if their
    // positions at the last build are unknown (collective on the steps where
    // LAMMPS checks); within: the rank's atoms are known to be within half
    // the skin (StabilityGuard::all_within())
    bool moved_too_far(int groupbit, bool every_atom_moved, bool within);

   private:
    bool stale_all;                // forces of all atoms after nfirst are stale
    bool held_moved;               // atoms after nfirst that sit out fine steps moved
    bool reference_lost;           // their positions at the last build are unknown
    std::vector<int> partners;     // owned atoms after nfirst in a fine interaction
    std::vector<int> movers;       // owned atoms after nfirst that move on fine steps
    ForceSampler::Touched fine;    // nfirst and partners

    void clear_all_forces();
    int beyond(const std::vector<int> *only, int groupbit) const;
    bigint outside(int bits) const;    // atoms with all these bits outside G (global)
  };

}    // namespace PEJump
}    // namespace LAMMPS_NS

#endif
