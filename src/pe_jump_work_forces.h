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

#ifndef LMP_PE_JUMP_WORK_FORCES_H
#define LMP_PE_JUMP_WORK_FORCES_H

#include "pointers.h"

#include <vector>

namespace LAMMPS_NS {
namespace PEJump {

  // Per-step work arrays of forces (3 values per atom), not migrated with
  // the atoms: an array exists only while the fix needs it, and all have
  // room for the same number of atoms
  class WorkForces : protected Pointers {
   public:
    WorkForces(class LAMMPS *, int count);
    ~WorkForces() override;

    // room for n atoms in the arrays k with bit (1 << k) in need; the
    // others are released
    void ensure(int n, int need);
    double **get(int k) const { return arrays[k]; }
    double memory_usage() const;

   private:
    std::vector<double **> arrays;
    int room, made;    // atoms with room, arrays made (bits)
  };

}    // namespace PEJump
}    // namespace LAMMPS_NS

#endif
