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

#include "pe_jump_split_tally.h"

#include "angle.h"
#include "atom.h"
#include "bond.h"
#include "compute.h"
#include "dihedral.h"
#include "force.h"
#include "improper.h"
#include "modify.h"
#include "pair.h"

#include <cstring>

using namespace LAMMPS_NS;
using namespace PEJump;

/* ----------------------------------------------------------------------
   the styles that the MD step computes: the pair style unless pair_modify
   compute no, the bonded styles in molecular systems
------------------------------------------------------------------------- */

double *SplitTally::tally(int part) const
{
  const bool bonded = (atom->molecular != Atom::ATOMIC);
  Pair *pair = (force->pair && force->pair->compute_flag) ? force->pair : nullptr;
  switch (part) {
    case 0:
      return pair ? &pair->eng_vdwl : nullptr;
    case 1:
      return pair ? &pair->eng_coul : nullptr;
    case 2:
      return (bonded && force->bond) ? &force->bond->energy : nullptr;
    case 3:
      return (bonded && force->angle) ? &force->angle->energy : nullptr;
    case 4:
      return (bonded && force->dihedral) ? &force->dihedral->energy : nullptr;
    default:
      return (bonded && force->improper) ? &force->improper->energy : nullptr;
  }
}

/* ---------------------------------------------------------------------- */

void SplitTally::init()
{
  usable = true;
  for (const auto *compute : modify->get_compute_list())
    for (const char *style : {"pair", "bond", "angle", "dihedral", "improper"})
      if (strcmp(compute->style, style) == 0) usable = false;
}

/* ---------------------------------------------------------------------- */

void SplitTally::keep()
{
  for (int part = 0; part < NPART; part++) {
    const double *e = tally(part);
    energy[part] = e ? *e : 0.0;
  }
  held = true;
}

/* ---------------------------------------------------------------------- */

void SplitTally::add()
{
  for (int part = 0; part < NPART; part++) {
    double *e = tally(part);
    if (e) *e += energy[part];
  }
  held = false;
  added = true;
}
