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

#include "pe_jump_atom_set.h"

#include "atom.h"
#include "atom_vec.h"
#include "comm.h"
#include "domain.h"
#include "error.h"
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
  sent.clear();
  received.clear();
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

/* ---------------------------------------------------------------------- */

void MovingGhosts::clear_forces()
{
  double *f = flat(atom->f);
  for (const auto &message : received)
    for (const int i : message.second) f[3 * i] = f[3 * i + 1] = f[3 * i + 2] = 0.0;
}

/* ----------------------------------------------------------------------
   the moving atoms of a message (known by key in messages), as mark()
   found them (nullptr for an empty message)
------------------------------------------------------------------------- */

template <typename Key>
const std::vector<int> *
MovingGhosts::atoms_of(const std::unordered_map<Key, std::vector<int>> &messages, Key key,
                       int n) const
{
  if (n == 0) return nullptr;
  const auto found = messages.find(key);
  if (found == messages.end())
    error->one(
        FLERR,
        "Fix {}: a ghost message of the fine steps that MovingGhosts::mark() did not see (bug)",
        fix->style);
  return &found->second;
}

/* ----------------------------------------------------------------------
   forward: the flags, or the positions of the moving atoms of list with
   the periodic shift of the message (as AtomVec::pack_comm())
------------------------------------------------------------------------- */

int MovingGhosts::pack_forward(int n, const int *list, double *buf, int pbc_flag, const int *pbc)
{
  if (mode == FLAGS) {
    std::vector<int> &atoms = sent[list];
    for (int i = 0; i < n; i++) {
      buf[i] = moving[list[i]];
      if (moving[list[i]]) atoms.push_back(list[i]);
    }
    return n;
  }
  const std::vector<int> *atoms = atoms_of(sent, list, n);
  if (!atoms) return 0;
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
  const double *x = flat(atom->x);
  int m = 0;
  for (const int j : *atoms) {
    buf[m++] = x[3 * j] + dx;
    buf[m++] = x[3 * j + 1] + dy;
    buf[m++] = x[3 * j + 2] + dz;
  }
  return m;
}

/* ---------------------------------------------------------------------- */

void MovingGhosts::unpack_forward(int n, int first, const double *buf)
{
  if (mode == FLAGS) {
    std::vector<int> &ghosts = received[first];
    for (int i = 0; i < n; i++) {
      moving[first + i] = static_cast<int>(buf[i]);
      if (moving[first + i]) ghosts.push_back(first + i);
    }
    return;
  }
  const std::vector<int> *ghosts = atoms_of(received, first, n);
  if (!ghosts) return;
  double *x = flat(atom->x);
  int m = 0;
  for (const int i : *ghosts) {
    x[3 * i] = buf[m++];
    x[3 * i + 1] = buf[m++];
    x[3 * i + 2] = buf[m++];
  }
}

/* ----------------------------------------------------------------------
   reverse: the forces on the moving ghosts (the only ones a fine
   evaluation acts on), added to their owners
------------------------------------------------------------------------- */

int MovingGhosts::pack_reverse(int n, int first, double *buf) const
{
  const std::vector<int> *ghosts = atoms_of(received, first, n);
  if (!ghosts) return 0;
  const double *f = flat(atom->f);
  int m = 0;
  for (const int i : *ghosts) {
    buf[m++] = f[3 * i];
    buf[m++] = f[3 * i + 1];
    buf[m++] = f[3 * i + 2];
  }
  return m;
}

/* ---------------------------------------------------------------------- */

void MovingGhosts::unpack_reverse(int n, const int *list, const double *buf)
{
  const std::vector<int> *atoms = atoms_of(sent, list, n);
  if (!atoms) return;
  double *f = flat(atom->f);
  int m = 0;
  for (const int j : *atoms) {
    f[3 * j] += buf[m++];
    f[3 * j + 1] += buf[m++];
    f[3 * j + 2] += buf[m++];
  }
}
