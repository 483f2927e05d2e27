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

#ifndef LMP_PE_JUMP_MOVING_GHOSTS_H
#define LMP_PE_JUMP_MOVING_GHOSTS_H

#include "pointers.h"

#include <unordered_map>
#include <vector>

namespace LAMMPS_NS {
class Fix;
namespace PEJump {

  // The ghost communication of a fine step of pe_jump/async. Only the
  // atoms that move on fine steps (the fine clock and the slow atoms in
  // fine interactions) change position between coarse nodes, and only
  // their ghost copies take part in fine interactions: a fine step sends
  // their positions to their ghost copies (forward) and their ghost
  // copies' forces back to their owners (reverse, newton on), instead of
  // those of every ghost as LAMMPS' own communication does. Each atom's
  // flag is sent to its ghost copies once after the lists are built or
  // the clocks change (mark()), so that sender and receiver agree on the
  // atoms of each message; both sides keep, per message, the atoms in it
  // that move, so that a fine step's messages pass over those atoms only
  // (a message is known by the send list it packs, or by the first ghost
  // it fills, which LAMMPS keeps until the next borders()). Atom styles
  // that communicate more than x forward or f in reverse (per-atom
  // torques, ...) are left to LAMMPS' communication (usable() is false).
  // The fix's pack/unpack functions hand over to this part while
  // active().
  class MovingGhosts : protected Pointers {
   public:
    MovingGhosts(class LAMMPS *, Fix *);

    bool usable() const;
    void mark(const int *moving_owned);    // the flags of the owned atoms (nlocal)
    void forward();
    void reverse();
    void clear_forces();    // of the moving ghosts (those reverse() sends)

    bool active() const { return mode != NONE; }
    int pack_forward(int n, const int *list, double *buf, int pbc_flag, const int *pbc);
    void unpack_forward(int n, int first, const double *buf);
    int pack_reverse(int n, int first, double *buf) const;
    void unpack_reverse(int n, const int *list, const double *buf);

   private:
    Fix *fix;
    enum { NONE, FLAGS, POSITIONS, FORCES } mode;
    std::vector<int> moving;    // owned and ghost atoms: 1 if the atom moves on fine steps
    // the moving atoms of each message: by its send list (the atoms it
    // sends forward and gets forces of) and by its first ghost (the ghost
    // copies it fills forward and sends forces from)
    std::unordered_map<const int *, std::vector<int>> sent;
    std::unordered_map<int, std::vector<int>> received;
    template <typename Key>
    const std::vector<int> *atoms_of(const std::unordered_map<Key, std::vector<int>> &messages,
                                     Key key, int n) const;
  };
}    // namespace PEJump
}    // namespace LAMMPS_NS

#endif
