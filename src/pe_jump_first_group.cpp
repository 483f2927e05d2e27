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

#include "pe_jump_first_group.h"

#include "atom.h"
#include "atom_vec.h"
#include "domain.h"
#include "error.h"
#include "force.h"
#include "group.h"
#include "neighbor.h"
#include "pair.h"
#include "pe_jump_stability_guard.h"
#include "update.h"

#include <cstring>

using namespace LAMMPS_NS;
using namespace LAMMPS_NS::PEJump;

/* ---------------------------------------------------------------------- */

FirstGroup::FirstGroup(LAMMPS *lmp) :
    Pointers(lmp), stale_all(true), held_moved(true), reference_lost(false), fine{0, &partners}
{
}

/* ----------------------------------------------------------------------
   neigh_modify include G (G not all): Verlet::force_clear() clears the
   first atom->nfirst owned atoms and the ghosts, Neighbor::check_distance()
   checks the first nfirst owned atoms, the pair lists hold pairs in G only
------------------------------------------------------------------------- */

bool FirstGroup::active() const
{
  return neighbor->includegroup > 0;
}

/* ---------------------------------------------------------------------- */

void FirstGroup::refuse_unsupported(const char *style) const
{
  if (!active()) return;
  const int include = neighbor->includegroup;
  if (!atom->firstgroupname || (group->find(atom->firstgroupname) != include))
    error->all(FLERR,
               "Fix {} with neigh_modify include {} needs atom_modify first with the same group",
               style, group->names[include]);
  if (group->dynamic[include])
    error->all(FLERR,
               "Fix {} cannot use the dynamic group {} as neigh_modify include group: its atoms "
               "must stay the same during a run",
               style, group->names[include]);
  if (domain->box_change)
    error->all(FLERR,
               "Fix {} with neigh_modify include does not support a box or processor "
               "subdomains that change during the run (fix deform, fix balance, barostats, ...): "
               "remove neigh_modify include (and atom_modify first)",
               style);
  // the pair lists hold only pairs of two atoms of the group: the pair
  // forces between the slow atoms, and those of the interface, would be lost
  if (force->pair && (group->count(include) < atom->natoms))
    error->all(FLERR,
               "Fix {}: with neigh_modify include {} LAMMPS builds pair lists of the pairs "
               "inside that group only, so the pair forces of the atoms outside it (pair style "
               "{}) would be lost. Use neigh_modify include only with bonded interactions (no "
               "pair style), or remove it (and atom_modify first)",
               style, group->names[include], force->pair_style);
}

/* ---------------------------------------------------------------------- */

bigint FirstGroup::outside(int bits) const
{
  const int includebit = group->bitmask[neighbor->includegroup];
  const int *mask = atom->mask;
  bigint local = 0, all = 0;
  for (int i = 0; i < atom->nlocal; i++)
    if (((mask[i] & bits) == bits) && !(mask[i] & includebit)) ++local;
  MPI_Allreduce(&local, &all, 1, MPI_LMP_BIGINT, MPI_SUM, world);
  return all;
}

/* ---------------------------------------------------------------------- */

void FirstGroup::require_all(int groupbit, const char *style) const
{
  if (!active()) return;
  const bigint count = outside(groupbit);
  if (count > 0)
    error->all(FLERR,
               "Fix {} moves every atom of its group every step, but {} of them are not in the "
               "neigh_modify include group {}: LAMMPS would neither clear their forces nor "
               "check their distances. Remove neigh_modify include (and atom_modify first), or "
               "use fix pe_jump/async with the include group on the fine clock",
               style, count, group->names[neighbor->includegroup]);
}

/* ---------------------------------------------------------------------- */

void FirstGroup::require_fine_clock(int groupbit, int clockbit, bool buffer) const
{
  if (!active()) return;
  const bigint count = outside(groupbit | clockbit);
  if (count > 0)
    error->all(FLERR,
               "Fix pe_jump/async: {} atoms on the fine clock (the fast group{}) are not in the "
               "neigh_modify include group {}: LAMMPS would neither clear their forces nor "
               "check their distances every step. Make the include group (and atom_modify "
               "first) contain the fast group{}, or remove neigh_modify include",
               count, buffer ? " and its buffer layers" : "", group->names[neighbor->includegroup],
               buffer ? " and its buffer layers (e.g. a region around the fast group)" : "");
}

/* ----------------------------------------------------------------------
   Neighbor::build() stored the positions of the first nfirst atoms in
   xhold (which has room for all owned atoms): the others' go to the rows
   LAMMPS does not use, so that checks of the fix read them there
------------------------------------------------------------------------- */

void FirstGroup::keep_build_positions()
{
  if (!active()) return;
  stale_all = true;    // atoms were exchanged and reordered, and f not with them
  held_moved = false;
  // called without a build at this step (a run with "pre no" after the
  // fix was defined): the build positions are gone; rebuild at the first check
  reference_lost = (neighbor->lastcall != update->ntimestep);
  double **xhold = neighbor->dist_check ? neighbor->get_xhold() : nullptr;
  if (!xhold) return;
  double **x = atom->x;
  for (int i = atom->nfirst; i < atom->nlocal; i++)
    for (int k = 0; k < 3; k++) xhold[i][k] = x[i][k];
}

/* ---------------------------------------------------------------------- */

void FirstGroup::find_partners(const int *participant, const int *moving, int groupbit)
{
  partners.clear();
  movers.clear();
  fine.nfirst = atom->nfirst;
  if (!active()) return;
  const int *mask = atom->mask;
  for (int i = atom->nfirst; i < atom->nlocal; i++) {
    if (participant[i]) partners.push_back(i);
    if ((mask[i] & groupbit) && moving[i]) movers.push_back(i);
  }
}

/* ---------------------------------------------------------------------- */

void FirstGroup::clear_before_setup()
{
  clear_all_forces();
  stale_all = true;
}

/* ---------------------------------------------------------------------- */

void FirstGroup::clear_all_forces()
{
  if (!active()) return;
  const int n = atom->nlocal - atom->nfirst;
  if (n > 0) {
    const size_t nbytes = sizeof(double) * n;
    memset(&atom->f[atom->nfirst][0], 0, 3 * nbytes);
    if (atom->avec->forceclearflag) atom->avec->force_clear(atom->nfirst, nbytes);
  }
  stale_all = false;
}

/* ---------------------------------------------------------------------- */

void FirstGroup::clear_stale_forces()
{
  if (!active()) return;
  if (stale_all) {
    clear_all_forces();
    return;
  }
  double **f = atom->f;
  const bool extra = atom->avec->forceclearflag;
  for (const int i : partners) {
    f[i][0] = f[i][1] = f[i][2] = 0.0;
    if (extra) atom->avec->force_clear(i, sizeof(double));
  }
}

/* ---------------------------------------------------------------------- */

bool FirstGroup::moved_too_far(int groupbit, bool every_atom_moved, bool within)
{
  if (!active()) return false;
  if (every_atom_moved) held_moved = true;
  if (reference_lost) {
    reference_lost = false;
    return true;
  }
  if (!StabilityGuard::lists_checked_now(neighbor)) return false;
  const bool all = held_moved;
  // at a coarse node the held atoms move on to the node at the step's end
  held_moved = every_atom_moved;
  const int local = within ? 0 : beyond(all ? nullptr : &movers, groupbit);
  int global = 0;
  MPI_Allreduce(&local, &global, 1, MPI_INT, MPI_MAX, world);
  return global != 0;
}

/* ----------------------------------------------------------------------
   1 if an atom after nfirst (of the fix group; those in only, if given)
   moved more than half the skin from xhold: the test of
   Neighbor::check_distance() with a box that does not change
------------------------------------------------------------------------- */

int FirstGroup::beyond(const std::vector<int> *only, int groupbit) const
{
  double **x = atom->x;
  double **xhold = neighbor->get_xhold();
  const double trigger = 0.5 * neighbor->skin;
  const double deltasq = trigger * trigger;
  const auto far = [&](int i) {
    const double dx = x[i][0] - xhold[i][0];
    const double dy = x[i][1] - xhold[i][1];
    const double dz = x[i][2] - xhold[i][2];
    return dx * dx + dy * dy + dz * dz > deltasq;
  };
  if (only) {
    for (const int i : *only)
      if (far(i)) return 1;
    return 0;
  }
  const int *mask = atom->mask;
  for (int i = atom->nfirst; i < atom->nlocal; i++)
    if ((mask[i] & groupbit) && far(i)) return 1;
  return 0;
}
