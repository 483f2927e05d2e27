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

#include "pe_jump_async_clocks.h"

#include "atom.h"
#include "pe_jump_atom_state.h"

using namespace LAMMPS_NS;
using namespace LAMMPS_NS::PEJump;

/* ---------------------------------------------------------------------- */

AsyncClocks::AsyncClocks(LAMMPS *lmp, AtomState &table, int k) :
    Pointers(lmp), state(table), TIME(table.add("tpos", 1, MOVING)), nfine(k), fine(0),
    elapsed(0.0), tnow(0.0)
{
}

/* ---------------------------------------------------------------------- */

double *AsyncClocks::times() const
{
  return state.val(TIME);
}

/* ----------------------------------------------------------------------
   the scheme starts a new coarse step: the atoms that sit out fine steps
   (caught up) are at its start
------------------------------------------------------------------------- */

void AsyncClocks::begin_coarse()
{
  fine = 0;
  elapsed = tnow = 0.0;
  double *t = times();
  for (int i = 0; i < atom->nlocal; i++)
    if (t[i] != MOVING) t[i] = 0.0;
}

/* ---------------------------------------------------------------------- */

void AsyncClocks::moving_at(double t)
{
  tnow = elapsed + t;
}

/* ----------------------------------------------------------------------
   after the last fine step of a coarse step the times start again at 0
------------------------------------------------------------------------- */

void AsyncClocks::end_fine(double h)
{
  if (last_fine_step()) {
    fine = 0;
    elapsed = 0.0;
  } else {
    ++fine;
    elapsed += h;
  }
  tnow = elapsed;
}

/* ---------------------------------------------------------------------- */

void AsyncClocks::hold(int i)
{
  double *t = times();
  if (t[i] == MOVING) t[i] = tnow;
}

/* ---------------------------------------------------------------------- */

void AsyncClocks::catch_up(int i, const FreeFlight &v, bool moving)
{
  double **x = atom->x;
  double *t = times();
  const double lag = tnow - t[i];
  if (lag != 0.0)
    for (int k = 0; k < 3; k++) x[i][k] += lag * v(i, k);
  t[i] = moving ? MOVING : tnow;
}

/* ---------------------------------------------------------------------- */

void AsyncClocks::catch_up_all(const FreeFlight &v, const int *moving)
{
  const double *t = times();
  for (int i = 0; i < atom->nlocal; i++)
    if (t[i] != MOVING) catch_up(i, v, moving && moving[i]);
}

/* ---------------------------------------------------------------------- */

void AsyncClocks::save(double *list) const
{
  list[0] = nfine;
  list[1] = fine;
  list[2] = elapsed;
}

/* ---------------------------------------------------------------------- */

bool AsyncClocks::restore(const double *list)
{
  if (static_cast<int>(list[0]) != nfine) return false;
  fine = static_cast<int>(list[1]);
  elapsed = tnow = list[2];
  return true;
}
