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

#include "pe_jump_moving_ghosts.h"

#include "atom.h"
#include "atom_vec.h"
#include "comm.h"
#include "domain.h"
#include "fix.h"

using namespace LAMMPS_NS;
using namespace LAMMPS_NS::PEJump;

/* ---------------------------------------------------------------------- */

MovingGhosts::MovingGhosts(LAMMPS *lmp, Fix *owner) : Pointers(lmp), fix(owner), mode(NONE) {}

/* ---------------------------------------------------------------------- */

bool MovingGhosts::usable() const
{
  return atom->avec->comm_x_only && atom->avec->comm_f_only && !comm->ghost_velocity;
}

/* ---------------------------------------------------------------------- */

void MovingGhosts::mark(const int *moving_owned)
{
  const int nlocal = atom->nlocal;
  moving.assign(nlocal + atom->nghost, 0);
  for (int i = 0; i < nlocal; i++) moving[i] = moving_owned[i];
  mode = FLAGS;
  comm->forward_comm(fix, 3);
  mode = NONE;
}

/* ---------------------------------------------------------------------- */

void MovingGhosts::forward()
{
  mode = POSITIONS;
  comm->forward_comm(fix, 3);
  mode = NONE;
}

/* ---------------------------------------------------------------------- */

void MovingGhosts::reverse()
{
  mode = FORCES;
  comm->reverse_comm(fix, 3);
  mode = NONE;
}

/* ----------------------------------------------------------------------
   forward: the flags, or the positions of the moving atoms of list with
   the periodic shift of the message (as AtomVec::pack_comm())
------------------------------------------------------------------------- */

int MovingGhosts::pack_forward(int n, const int *list, double *buf, int pbc_flag,
                               const int *pbc) const
{
  if (mode == FLAGS) {
    for (int i = 0; i < n; i++) buf[i] = moving[list[i]];
    return n;
  }
  double dx = 0.0, dy = 0.0, dz = 0.0;
  if (pbc_flag && !domain->triclinic) {
    dx = pbc[0] * domain->xprd;
    dy = pbc[1] * domain->yprd;
    dz = pbc[2] * domain->zprd;
  } else if (pbc_flag) {
    dx = pbc[0] * domain->xprd + pbc[5] * domain->xy + pbc[4] * domain->xz;
    dy = pbc[1] * domain->yprd + pbc[3] * domain->yz;
    dz = pbc[2] * domain->zprd;
  }
  double **x = atom->x;
  int m = 0;
  for (int i = 0; i < n; i++) {
    const int j = list[i];
    if (!moving[j]) continue;
    buf[m++] = x[j][0] + dx;
    buf[m++] = x[j][1] + dy;
    buf[m++] = x[j][2] + dz;
  }
  return m;
}

/* ---------------------------------------------------------------------- */

void MovingGhosts::unpack_forward(int n, int first, const double *buf)
{
  if (mode == FLAGS) {
    for (int i = 0; i < n; i++) moving[first + i] = static_cast<int>(buf[i]);
    return;
  }
  double **x = atom->x;
  int m = 0;
  for (int i = first; i < first + n; i++) {
    if (!moving[i]) continue;
    x[i][0] = buf[m++];
    x[i][1] = buf[m++];
    x[i][2] = buf[m++];
  }
}

/* ----------------------------------------------------------------------
   reverse: the forces on the moving ghosts (the only ones a fine
   evaluation acts on), added to their owners
------------------------------------------------------------------------- */

int MovingGhosts::pack_reverse(int n, int first, double *buf) const
{
  double **f = atom->f;
  int m = 0;
  for (int i = first; i < first + n; i++) {
    if (!moving[i]) continue;
    buf[m++] = f[i][0];
    buf[m++] = f[i][1];
    buf[m++] = f[i][2];
  }
  return m;
}

/* ---------------------------------------------------------------------- */

void MovingGhosts::unpack_reverse(int n, const int *list, const double *buf)
{
  double **f = atom->f;
  int m = 0;
  for (int i = 0; i < n; i++) {
    const int j = list[i];
    if (!moving[j]) continue;
    f[j][0] += buf[m++];
    f[j][1] += buf[m++];
    f[j][2] += buf[m++];
  }
}
