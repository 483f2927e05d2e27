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

#include "pe_jump_interaction_split.h"

#include "atom.h"
#include "error.h"
#include "force.h"
#include "neigh_list.h"
#include "neighbor.h"
#include "pair.h"
#include "pe_jump_errors.h"
#include "update.h"
#include "utils.h"

#include <algorithm>
#include <cmath>
#include <cstring>
#include <functional>
#include <memory>
#include <utility>

using namespace LAMMPS_NS;
using namespace LAMMPS_NS::PEJump;

static constexpr double ADDITIVE_TOLERANCE = 1.0e-12;    // relative, of the largest force

namespace {
// a neighbor list cut to the entries [first, first + count) of the row of
// atom i, or to no pair at all (i < 0), and put back as it was when this goes
class RowCut {
 public:
  RowCut(NeighList *cut, int i, int first, int count) :
      list(cut), inum(cut->inum), ilist(cut->ilist), atom(i), n_i(0), neigh_i(nullptr)
  {
    list->inum = 0;
    if (i < 0) return;
    n_i = list->numneigh[i];
    neigh_i = list->firstneigh[i];
    list->inum = 1;
    list->ilist = &atom;
    list->numneigh[i] = count;
    list->firstneigh[i] = neigh_i + first;
  }
  ~RowCut()
  {
    list->inum = inum;
    list->ilist = ilist;
    if (atom < 0) return;
    list->numneigh[atom] = n_i;
    list->firstneigh[atom] = neigh_i;
  }
  RowCut(const RowCut &) = delete;
  RowCut &operator=(const RowCut &) = delete;

 private:
  NeighList *list;
  int inum;
  int *ilist;
  int atom;
  int n_i;
  int *neigh_i;
};

// the forces on all atoms (owned and ghost) that compute() writes from zero
std::vector<double> forces_of(Atom *atom, const std::function<void()> &compute)
{
  const int n = 3 * (atom->nlocal + atom->nghost);
  double **f = atom->f;
  if (n) std::fill(&f[0][0], &f[0][0] + n, 0.0);
  compute();
  return n ? std::vector<double>(&f[0][0], &f[0][0] + n) : std::vector<double>();
}

// a force on an atom other than i and j (-1: none) after compute()
bool forces_beyond(Atom *atom, int i, int j, const std::function<void()> &compute)
{
  const std::vector<double> f = forces_of(atom, compute);
  for (size_t n = 0; 3 * n < f.size(); n++)
    if ((static_cast<int>(n) != i) && (static_cast<int>(n) != j) &&
        ((f[3 * n] != 0.0) || (f[3 * n + 1] != 0.0) || (f[3 * n + 2] != 0.0)))
      return true;
  return false;
}

// the pair style that requested a list, if it computes from that list: a
// run stopped by an error leaves a second request of the style behind, a
// copy of its list that the style may not use (cutting that one cuts
// nothing the style sees)
Pair *style_using(NeighList *list)
{
  if (list->requestor_type != NeighList::PAIR) return nullptr;
  auto *style = static_cast<Pair *>(list->requestor);
  return (style && (style->list == list)) ? style : nullptr;
}
}    // namespace

/* ---------------------------------------------------------------------- */

InteractionSplit::InteractionSplit(LAMMPS *lmp, int group, int fast) :
    Pointers(lmp), groupbit(group), finebit(fast), current(NONE), hybrid_topology(0), saved_ago(0),
    built_at(-1), topology(0)
{
  frac[FINE] = frac[COARSE] = 0.0;
  topo[0] = {0, &neighbor->nbondlist, &neighbor->bondlist, 2, 0, nullptr, 0};
  topo[1] = {0, &neighbor->nanglelist, &neighbor->anglelist, 3, 0, nullptr, 0};
  topo[2] = {0, &neighbor->ndihedrallist, &neighbor->dihedrallist, 4, 0, nullptr, 0};
  topo[3] = {0, &neighbor->nimproperlist, &neighbor->improperlist, 4, 0, nullptr, 0};
}

/* ---------------------------------------------------------------------- */

InteractionSplit::~InteractionSplit()
{
  restore();
}

int InteractionSplit::fine(int i) const
{
  const int m = atom->mask[i];
  return (m & groupbit) && (m & finebit);
}

/* ---------------------------------------------------------------------- */

int InteractionSplit::coarse(int i) const
{
  const int m = atom->mask[i];
  return (m & groupbit) && !(m & finebit);
}

/* ---------------------------------------------------------------------- */

bool InteractionSplit::up_to_date() const
{
  return built_at == neighbor->ncalls;
}

/* ---------------------------------------------------------------------- */

bigint InteractionSplit::topology_count() const
{
  if (atom->molecular == Atom::ATOMIC) return 0;
  return atom->nbonds + atom->nangles + atom->ndihedrals + atom->nimpropers;
}

/* ---------------------------------------------------------------------- */

void InteractionSplit::start_run()
{
  topology = topology_count();
}

/* ---------------------------------------------------------------------- */

void InteractionSplit::check_topology() const
{
  if (topology_count() != topology)
    error->all(FLERR,
               "Fix pe_jump/async: the bonds, angles, dihedrals or impropers changed during the "
               "run (from {} to {}). Use fix pe_jump{}",
               topology, topology_count(), errorurl(55));
}

/* ---------------------------------------------------------------------- */

void InteractionSplit::build()
{
  restore();
  built_at = neighbor->ncalls;

  // perpetual neighbor lists requested by pair styles (one for a plain pair
  // style, one per sub-style for pair hybrid)

  // the subsets of the last build are refilled (their storage is kept)
  size_t npairs = 0;
  cross.clear();
  label_clocks();
  for (int n = 0; n < neighbor->nlist; n++) {
    NeighList *list = neighbor->lists[n];
    if (!list || list->occasional || (list->requestor_type != NeighList::PAIR)) continue;
    if (pairs.size() <= npairs) pairs.emplace_back();
    pairs[npairs].list = list;
    split_pairs(pairs[npairs++]);
  }
  pairs.resize(npairs);

  double local[3] = {0.0, 0.0, 0.0};    // interactions: fine, coarse, all
  for (const auto &p : pairs)
    for (int s = 0; s < 2; s++)
      for (const int i : p.part[s].ilist) local[s] += p.part[s].numneigh[i];

  const bool molecular = (atom->molecular != Atom::ATOMIC);
  topo[0].on = molecular && force->bond;
  topo[1].on = molecular && force->angle;
  topo[2].on = molecular && force->dihedral;
  topo[3].on = molecular && force->improper;
  hybrid_topology = (topo[0].on && utils::strmatch(force->bond_style, "^hybrid")) ||
      (topo[1].on && utils::strmatch(force->angle_style, "^hybrid")) ||
      (topo[2].on && utils::strmatch(force->dihedral_style, "^hybrid")) ||
      (topo[3].on && utils::strmatch(force->improper_style, "^hybrid"));
  for (auto &t : topo) {
    if (t.on) {
      split_topology(t);
      local[FINE] += t.nfine;
      local[COARSE] += t.nfull - t.nfine;
    }
  }
  local[2] = local[FINE] + local[COARSE];

  double global[3];
  MPI_Allreduce(local, global, 3, MPI_DOUBLE, MPI_SUM, world);
  for (int s = 0; s < 2; s++) frac[s] = (global[2] > 0.0) ? global[s] / global[2] : 0.0;
}

/* ---------------------------------------------------------------------- */

void InteractionSplit::split_pairs(PairList &p)
{
  NeighList *list = p.list;
  const int nall = atom->nlocal + atom->nghost;
  const int inum = list->inum;
  const int *ilist = list->ilist;

  // one buffer for both subsets: the FINE neighbors of the atoms in list
  // order from its front, the COARSE ones from its back (each atom's in
  // list order), so that it is sized once and filled in one pass
  size_t total = 0;
  for (int ii = 0; ii < inum; ii++) total += list->numneigh[ilist[ii]];
  p.neigh.resize(total);
  int *front = p.neigh.data();
  int *back = front + total;
  for (auto &part : p.part) {
    part.ilist.clear();
    part.numneigh.assign(nall, 0);
    part.firstneigh.assign(nall, nullptr);
  }
  PairSubset &fine = p.part[FINE], &coarse = p.part[COARSE];

  for (int ii = 0; ii < inum; ii++) {
    const int i = ilist[ii];
    const int n = list->numneigh[i];
    const int nfine = sort_neighbors(i, list->firstneigh[i], n, front, back);
    if (nfine > 0) {
      fine.ilist.push_back(i);
      fine.numneigh[i] = nfine;
      fine.firstneigh[i] = front;
      front += nfine;
    }
    if (nfine < n) {
      back -= n - nfine;
      coarse.ilist.push_back(i);
      coarse.numneigh[i] = n - nfine;
      coarse.firstneigh[i] = back;
    }
  }
}

/* ----------------------------------------------------------------------
   per atom (owned and ghost) 1 if on the fine clock, 2 if on the coarse
   clock, 0 if not integrated: a pair is FINE if either atom is fine
------------------------------------------------------------------------- */

void InteractionSplit::label_clocks()
{
  const int *mask = atom->mask;
  const int nall = atom->nlocal + atom->nghost;
  clock_of.resize(nall);
  for (int i = 0; i < nall; i++)
    clock_of[i] = !(mask[i] & groupbit) ? 0 : ((mask[i] & finebit) ? 1 : 2);
}

/* ----------------------------------------------------------------------
   the n neighbors of atom i at jlist: the FINE ones to fine_at, the
   COARSE ones to the places just before coarse_end, each in list order;
   the FINE pairs of a fine and a coarse atom are noted in cross. Returns
   the number of FINE ones
------------------------------------------------------------------------- */

int InteractionSplit::sort_neighbors(int i, const int *jlist, int n, int *fine_at, int *coarse_end)
{
  if (n <= 0) return 0;
  const int *clock = clock_of.data();
  int nfine = n;
  if (clock[i] != 1) {
    nfine = 0;
    for (int jj = 0; jj < n; jj++) nfine += (clock[jlist[jj] & NEIGHMASK] == 1);
  }
  int *coarse_at = coarse_end - (n - nfine);
  if (nfine == n) {
    std::copy(jlist, jlist + n, fine_at);
  } else if (nfine == 0) {
    std::copy(jlist, jlist + n, coarse_at);
  } else {
    int *f = fine_at, *c = coarse_at;
    for (int jj = 0; jj < n; jj++) *((clock[jlist[jj] & NEIGHMASK] == 1) ? f++ : c++) = jlist[jj];
  }
  for (int jj = 0; jj < nfine; jj++) {
    const int j = fine_at[jj] & NEIGHMASK;
    if ((clock[i] == 2) || (clock[j] == 2)) {
      cross.push_back(i);
      cross.push_back(j);
    }
  }
  return nfine;
}

/* ---------------------------------------------------------------------- */

void InteractionSplit::split_topology(TopoList &t)
{
  t.nfull = *t.count;
  t.full = *t.list;
  t.nfine = 0;
  if (t.nfull == 0) return;
  const int width = t.natoms + 1;    // atoms and type
  // the entries are one array (see TopoList); entry n starts at row(n)
  int *rows = t.full[0];
  const auto row = [rows, width](int n) {
    return rows + static_cast<size_t>(n) * width;
  };
  // FINE if any of the atoms of entry n is on the fine clock (label_clocks())
  const int *clock = clock_of.data();
  const auto is_fine = [&](int n) {
    const int *entry = row(n);
    for (int k = 0; k < t.natoms; k++)
      if (clock[entry[k]] == 1) return true;
    return false;
  };

  // a stable partition: the coarse entries behind the last fine one stay
  // where they are, the others move in runs
  int last = t.nfull - 1;
  while ((last >= 0) && !is_fine(last)) --last;
  coarse_entries.clear();
  for (int n = 0; n <= last;) {
    int m = n;
    while ((m <= last) && is_fine(m)) ++m;
    if (t.nfine != n) std::copy(row(n), row(m), row(t.nfine));
    t.nfine += m - n;
    for (n = m; (m <= last) && !is_fine(m);) ++m;
    coarse_entries.insert(coarse_entries.end(), row(n), row(m));
    n = m;
  }
  std::copy(coarse_entries.begin(), coarse_entries.end(), row(t.nfine));
}

/* ---------------------------------------------------------------------- */

InteractionSplit::PairFit InteractionSplit::pair_fit()
{
  if (!force->pair || !force->pair->compute_flag || pairs.empty()) return FITS;
  restore();
  double **f = atom->f;
  const int nall = atom->nlocal + atom->nghost;
  std::vector<double> fkeep(3 * nall);
  if (nall) std::copy(&f[0][0], &f[0][0] + 3 * nall, fkeep.begin());
  // every rank evaluates the styles equally often (a style may communicate
  // inside compute()), and the ranks agree after each stage
  const auto agree = [&](bool mine, PairFit verdict) {
    int local = mine ? verdict : FITS, all = FITS;
    MPI_Allreduce(&local, &all, 1, MPI_INT, MPI_MAX, world);
    return static_cast<PairFit>(all);
  };
  PairFit fit = agree(forces_off_lists(), OFF_LISTS);
  if (fit == FITS) fit = agree(forces_off_pairs(), OFF_PAIRS);
  if (fit == FITS) {
    bool all_additive = true;
    for (auto &p : pairs) all_additive = additive(p.list) && all_additive;
    fit = agree(!all_additive, NOT_ADDITIVE);
  }
  if (fit == FITS) fit = agree(depends_on_time(), ON_TIME);
  if (nall) std::copy(fkeep.begin(), fkeep.end(), &f[0][0]);
  return fit;
}

/* ----------------------------------------------------------------------
   pair_fit(): a force after one evaluation with every list empty (put
   back in the reverse order: lists may share arrays)
------------------------------------------------------------------------- */

bool InteractionSplit::forces_off_lists()
{
  std::vector<std::unique_ptr<RowCut>> cuts;
  for (auto &p : pairs) cuts.push_back(std::make_unique<RowCut>(p.list, -1, 0, 0));
  const bool beyond = forces_beyond(atom, -1, -1, [&]() {
    force->pair->compute(0, 0);
  });
  while (!cuts.empty()) cuts.pop_back();
  return beyond;
}

/* ----------------------------------------------------------------------
   pair_fit(): each list cut to one pair per atom type (or to none where
   this rank has no pair of the type), evaluated by its style alone: a
   force on another atom than the two of the pair
------------------------------------------------------------------------- */

bool InteractionSplit::forces_off_pairs()
{
  bool beyond = false;
  for (auto &p : pairs) {
    NeighList *list = p.list;
    Pair *style = style_using(list);
    if (!style) continue;
    for (const auto &ij : probe_pairs(list)) {
      const int j = (ij.first < 0) ? -1 : (list->firstneigh[ij.first][ij.second] & NEIGHMASK);
      const RowCut cut(list, ij.first, ij.second, 1);
      if (forces_beyond(atom, ij.first, j, [&]() {
            style->compute(0, 0);
          }))
        beyond = true;
    }
  }
  return beyond;
}

/* ----------------------------------------------------------------------
   the forces of the style of a list on the first two pairs of an atom
   together are those on each pair alone, summed (to round-off): a style
   whose pair forces depend on the other pairs of the atoms (local
   densities) cannot be split pair by pair. The style of the list is
   evaluated alone
------------------------------------------------------------------------- */

bool InteractionSplit::additive(NeighList *list)
{
  Pair *style = style_using(list);
  if (!style) return true;
  int atom_i = -1;
  for (int ii = 0; (ii < list->inum) && (atom_i < 0); ii++)
    if (list->numneigh[list->ilist[ii]] >= 2) atom_i = list->ilist[ii];
  const auto forces = [&](int first, int count) {
    const RowCut cut(list, atom_i, (atom_i < 0) ? 0 : first, (atom_i < 0) ? 0 : count);
    return forces_of(atom, [&]() {
      style->compute(0, 0);
    });
  };
  const std::vector<double> both = forces(0, 2), one = forces(0, 1), other = forces(1, 1);
  double scale = 0.0, worst = 0.0;
  for (size_t k = 0; k < both.size(); k++) {
    scale = std::max(scale, std::fabs(both[k]));
    worst = std::max(worst, std::fabs(both[k] - (one[k] + other[k])));
  }
  return worst <= ADDITIVE_TOLERANCE * scale;
}

/* ----------------------------------------------------------------------
   the forces of the pair style with every list cut to one pair, at this
   step and 1, 7, half the run's and the run's steps later (the time moves
   with the step): different if a variable of the time or the step scales
   them (one that is the same at all of these steps is not seen)
------------------------------------------------------------------------- */

bool InteractionSplit::depends_on_time()
{
  // (put back in the reverse order: lists may share arrays)
  std::vector<std::unique_ptr<RowCut>> cuts;
  for (auto &p : pairs) {
    const auto probes = probe_pairs(p.list);
    auto first = std::make_pair(-1, 0);
    for (const auto &ij : probes)
      if ((first.first < 0) && (ij.first >= 0)) first = ij;
    cuts.push_back(std::make_unique<RowCut>(p.list, first.first, first.second, 1));
  }
  const auto forces = [&]() {
    return forces_of(atom, [&]() {
      force->pair->compute(0, 0);
    });
  };
  // bit for bit (NaN from atoms on top of each other compares unequal)
  const std::vector<double> now = forces();
  const bigint run = update->laststep - update->ntimestep;
  bool differ = false;
  for (const bigint later : {bigint(1), bigint(7), run / 2, run}) {
    if (differ || (later <= 0)) continue;
    update->ntimestep += later;
    const std::vector<double> then = forces();
    update->ntimestep -= later;
    differ =
        !now.empty() && (std::memcmp(now.data(), then.data(), now.size() * sizeof(double)) != 0);
  }
  while (!cuts.empty()) cuts.pop_back();
  return differ;
}

/* ----------------------------------------------------------------------
   per atom type, the closest pair of a list with an atom i of that type:
   i and the index of the neighbor in its row (a style may treat types
   apart, e.g. TIP4P its oxygen), or (-1, 0) where this rank has no pair
   with an atom of the type: one entry per type on every rank
------------------------------------------------------------------------- */

std::vector<std::pair<int, int>> InteractionSplit::probe_pairs(const NeighList *list) const
{
  double **x = atom->x;
  const int *type = atom->type;
  std::vector<double> best(atom->ntypes + 1, -1.0);
  std::vector<std::pair<int, int>> chosen(best.size(), {-1, 0});
  for (int ii = 0; ii < list->inum; ii++) {
    const int i = list->ilist[ii];
    for (int jj = 0; jj < list->numneigh[i]; jj++) {
      const int j = list->firstneigh[i][jj] & NEIGHMASK;
      double r2 = 0.0;
      for (int k = 0; k < 3; k++) r2 += (x[i][k] - x[j][k]) * (x[i][k] - x[j][k]);
      if ((best[type[i]] < 0.0) || (r2 < best[type[i]])) {
        best[type[i]] = r2;
        chosen[type[i]] = {i, jj};
      }
    }
  }
  chosen.erase(chosen.begin());    // (types count from 1)
  return chosen;
}

/* ---------------------------------------------------------------------- */

void InteractionSplit::activate(Subset which)
{
  restore();
  if (hybrid_topology) {
    saved_ago = neighbor->ago;
    neighbor->ago = 0;
  }
  current = which;
  if (which == ALL) return;
  for (auto &p : pairs) {
    p.inum = p.list->inum;
    p.ilist = p.list->ilist;
    p.numneigh = p.list->numneigh;
    p.firstneigh = p.list->firstneigh;
    p.list->inum = static_cast<int>(p.part[which].ilist.size());
    p.list->ilist = p.part[which].ilist.data();
    p.list->numneigh = p.part[which].numneigh.data();
    p.list->firstneigh = p.part[which].firstneigh.data();
  }
  for (auto &t : topo) {
    if (!t.on) continue;
    *t.count = (which == FINE) ? t.nfine : t.nfull - t.nfine;
    *t.list = (which == FINE) ? t.full : t.full + t.nfine;
  }
}

/* ---------------------------------------------------------------------- */

void InteractionSplit::restore()
{
  if (current == NONE) return;
  if (hybrid_topology) neighbor->ago = saved_ago;
  if (current == ALL) {
    current = NONE;
    return;
  }
  for (auto &p : pairs) {
    p.list->inum = p.inum;
    p.list->ilist = p.ilist;
    p.list->numneigh = p.numneigh;
    p.list->firstneigh = p.firstneigh;
  }
  for (auto &t : topo) {
    if (!t.on) continue;
    *t.count = t.nfull;
    *t.list = t.full;
  }
  current = NONE;
}

/* ---------------------------------------------------------------------- */

void InteractionSplit::mark_interface(std::vector<int> &flag) const
{
  const int nall = atom->nlocal + atom->nghost;
  flag.assign(nall, 0);

  if (force->pair)
    for (size_t n = 0; n < cross.size(); n += 2) {
      const int i = cross[n], j = cross[n + 1];
      if (within_cutoff(i, j)) {
        if (fine(i)) flag[i] = 1;
        if (fine(j)) flag[j] = 1;
      }
    }

  for (const auto &t : topo) {
    if (!t.on) continue;
    for (int n = 0; n < t.nfine; n++) {
      const int *entry = t.full[n];
      bool slow = false;
      for (int k = 0; k < t.natoms; k++) slow = slow || coarse(entry[k]);
      if (!slow) continue;
      for (int k = 0; k < t.natoms; k++)
        if (fine(entry[k])) flag[entry[k]] = 1;
    }
  }
}

/* ----------------------------------------------------------------------
   atoms i and j (owned or ghost) closer than the pair style's cutoff, and
   than reach if reach > 0
------------------------------------------------------------------------- */

bool InteractionSplit::within_cutoff(int i, int j, double reach) const
{
  double **x = atom->x;
  const int *type = atom->type;
  const double dx = x[i][0] - x[j][0];
  const double dy = x[i][1] - x[j][1];
  const double dz = x[i][2] - x[j][2];
  const double rsq = dx * dx + dy * dy + dz * dz;
  return (rsq < force->pair->cutsq[type[i]][type[j]]) && ((reach <= 0.0) || (rsq < reach * reach));
}

/* ----------------------------------------------------------------------
   the atoms of the FINE interactions: all pairs of the lists, or (acting)
   only those closer than the cutoff (and than reach, if reach > 0)
------------------------------------------------------------------------- */

void InteractionSplit::mark_fine(std::vector<int> &flag, bool acting, double reach) const
{
  flag.assign(atom->nlocal + atom->nghost, 0);
  for (const auto &p : pairs) {
    const auto &part = p.part[FINE];
    for (const int i : part.ilist) {
      for (int jj = 0; jj < part.numneigh[i]; jj++) {
        const int j = part.firstneigh[i][jj] & NEIGHMASK;
        if (!acting || within_cutoff(i, j, reach)) flag[i] = flag[j] = 1;
      }
    }
  }
  for (const auto &t : topo) {
    if (!t.on) continue;
    for (int n = 0; n < t.nfine; n++)
      for (int k = 0; k < t.natoms; k++) flag[t.full[n][k]] = 1;
  }
}
