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

#include "pe_jump_atom_state.h"

#include "atom.h"
#include "memory.h"

#include <utility>

using namespace LAMMPS_NS;
using namespace LAMMPS_NS::PEJump;

/* ---------------------------------------------------------------------- */

AtomState::AtomState(LAMMPS *lmp) : Pointers(lmp), capacity(0) {}

/* ---------------------------------------------------------------------- */

AtomState::~AtomState()
{
  for (auto &f : fields) {
    memory->destroy(f.vec);
    memory->destroy(f.val);
  }
}

/* ---------------------------------------------------------------------- */

int AtomState::add(const std::string &name, int width, double init)
{
  fields.push_back({name, width, init, nullptr, nullptr});
  if (capacity) grow(fields.back(), 0, capacity);
  return static_cast<int>(fields.size()) - 1;
}

/* ---------------------------------------------------------------------- */

void AtomState::ensure(int n)
{
  if (n <= capacity) return;
  // a little room ahead, so that atoms arriving one by one do not
  // reallocate every time
  const int room = n + n / 16 + 64;
  for (auto &f : fields) grow(f, capacity, room);
  capacity = room;
}

/* ----------------------------------------------------------------------
   field f from room for atoms 0 .. from-1 to 0 .. to-1, the new ones at init
------------------------------------------------------------------------- */

void AtomState::grow(Field &f, int from, int to)
{
  const std::string what = "pe_jump:" + f.name;
  if (f.width == 1)
    memory->grow(f.val, to, what.c_str());
  else
    memory->grow(f.vec, to, f.width, what.c_str());
  for (int i = from; i < to; i++) fill(f, i);
}

/* ---------------------------------------------------------------------- */

void AtomState::fill(Field &f, int i)
{
  if (f.width == 1)
    f.val[i] = f.init;
  else
    for (int k = 0; k < f.width; k++) f.vec[i][k] = f.init;
}

/* ---------------------------------------------------------------------- */

void AtomState::swap(int field1, int field2)
{
  std::swap(fields[field1].vec, fields[field2].vec);
  std::swap(fields[field1].val, fields[field2].val);
}

/* ---------------------------------------------------------------------- */

void AtomState::copy(int i, int j)
{
  ensure((i > j ? i : j) + 1);
  for (auto &f : fields) {
    if (f.width == 1)
      f.val[j] = f.val[i];
    else
      for (int k = 0; k < f.width; k++) f.vec[j][k] = f.vec[i][k];
  }
}

/* ---------------------------------------------------------------------- */

void AtomState::reset(int i)
{
  ensure(i + 1);
  for (auto &f : fields) fill(f, i);
}

/* ---------------------------------------------------------------------- */

int AtomState::pack(int i, double *buf) const
{
  int m = 0;
  for (const auto &f : fields) {
    if (f.width == 1)
      buf[m++] = f.val[i];
    else
      for (int k = 0; k < f.width; k++) buf[m++] = f.vec[i][k];
  }
  return m;
}

/* ---------------------------------------------------------------------- */

int AtomState::unpack(int i, const double *buf)
{
  ensure(i + 1);
  int m = 0;
  for (auto &f : fields) {
    if (f.width == 1)
      f.val[i] = buf[m++];
    else
      for (int k = 0; k < f.width; k++) f.vec[i][k] = buf[m++];
  }
  return m;
}

/* ---------------------------------------------------------------------- */

int AtomState::values() const
{
  int n = 0;
  for (const auto &f : fields) n += f.width;
  return n;
}

/* ---------------------------------------------------------------------- */

double AtomState::memory_usage() const
{
  return static_cast<double>(capacity) * values() * sizeof(double);
}

/* ---------------------------------------------------------------------- */

int AtomState::pack_restart(int i, double *buf) const
{
  buf[0] = restart_size();
  pack(i, &buf[1]);
  return restart_size();
}

/* ---------------------------------------------------------------------- */

bool AtomState::unpack_restart(int nlocal, int nth)
{
  double **extra = atom->extra;
  int m = 0;
  for (int i = 0; i < nth; i++) m += static_cast<int>(extra[nlocal][m]);
  if (static_cast<int>(extra[nlocal][m]) != restart_size()) return false;
  unpack(nlocal, &extra[nlocal][m + 1]);
  return true;
}
