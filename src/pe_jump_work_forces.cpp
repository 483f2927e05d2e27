/* ----------------------------------------------------------------------
   LAMMPS - Large-scale Atomic/Molecular Massively Parallel Simulator
   https://www.lammps.org/, Sandia National Laboratories
   LAMMPS development team: developers@lammps.org

   Copyright (2003) Sandia Corporation.  Under the terms of Contract
   DE-AC04-94AL85000 with Sandia Corporation, the U.S. Government retains
   certain rights in this software.  This software is distributed under
   the GNU General Public License.

   See the README file in the top-level LAMMPS directory.
------------------------------------------------------------------------- */

#include "pe_jump_work_forces.h"

#include "memory.h"

#include <string>

using namespace LAMMPS_NS;
using namespace LAMMPS_NS::PEJump;

/* ---------------------------------------------------------------------- */

WorkForces::WorkForces(LAMMPS *lmp, int count) :
    Pointers(lmp), arrays(count, nullptr), room(0), made(0)
{
}

/* ---------------------------------------------------------------------- */

WorkForces::~WorkForces()
{
  for (auto &a : arrays) memory->destroy(a);
}

/* ---------------------------------------------------------------------- */

void WorkForces::ensure(int n, int need)
{
  if ((n <= room) && (need == made)) return;
  if (n > room) room = n + n / 16 + 64;
  for (int k = 0; k < static_cast<int>(arrays.size()); k++) {
    memory->destroy(arrays[k]);
    if (need & (1 << k))
      memory->create(arrays[k], room, 3, ("pe_jump:work" + std::to_string(k)).c_str());
  }
  made = need;
}

/* ---------------------------------------------------------------------- */

double WorkForces::memory_usage() const
{
  int count = 0;
  for (const auto *a : arrays) count += a ? 1 : 0;
  return static_cast<double>(room) * 3 * sizeof(double) * count;
}
