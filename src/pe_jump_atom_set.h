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

#ifndef LMP_PE_JUMP_ATOM_SET_H
#define LMP_PE_JUMP_ATOM_SET_H

#include <vector>

namespace LAMMPS_NS {
namespace PEJump {

  using AtomList = std::vector<int>;

  // The values of a per-atom array of rows of three (LAMMPS' x, v, f and
  // the fixes' own, all allocated as one block) as one flat array: atom i's
  // values are [3 i, 3 i + 3). A loop over a list of scattered atoms then
  // reads no row pointer (a cache line of its own per atom)
  inline double *flat(double **rows)
  {
    return rows ? rows[0] : nullptr;
  }

  // The owned atoms of a fix group, or a list of them (local indices)
  struct AtomSet {
    int groupbit;
    const AtomList *list;

    // apply one(i) to the atoms of the set; mask and nlocal of class Atom
    template <typename Function> void each(const int *mask, int nlocal, Function &&one) const
    {
      if (list) {
        for (const int i : *list) one(i);
        return;
      }
      for (int i = 0; i < nlocal; i++)
        if (mask[i] & groupbit) one(i);
    }
  };

  // Free-flight velocities v^{n+1/2} of the owned atoms: atom->v, where
  // an atom is inside its step, or its node velocity plus half its jump,
  // where at_node[i] != 0 or for all atoms if all_at_node
  struct FreeFlight {
    double **v;
    double **jump;
    const int *at_node;
    bool all_at_node = false;
    double operator()(int i, int k) const
    {
      // (through the first row: see flat())
      const int at = 3 * i + k;
      return (all_at_node || (at_node && at_node[i])) ? v[0][at] + 0.5 * jump[0][at] : v[0][at];
    }
  };

}    // namespace PEJump
}    // namespace LAMMPS_NS

#endif
