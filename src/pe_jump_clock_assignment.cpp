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

#include "pe_jump_clock_assignment.h"

#include "atom.h"
#include "comm.h"
#include "compute.h"
#include "dump.h"
#include "error.h"
#include "fix.h"
#include "group.h"
#include "modify.h"
#include "neighbor.h"
#include "output.h"
#include "pe_jump_atom_state.h"
#include "pe_jump_errors.h"
#include "pe_jump_interaction_split.h"
#include "update.h"

#include <cmath>
#include <cstdint>

using namespace LAMMPS_NS;
using namespace LAMMPS_NS::PEJump;

// shares of the group's kinetic energy that the clock changes may add to
// the pseudo-energy (since the fix was defined) before a warning, and
// before an error
static constexpr double CHANGE_ENERGY_WARN = 0.05;
static constexpr double CHANGE_ENERGY_STOP = 0.5;

/* ---------------------------------------------------------------------- */

ClockAssignment::ClockAssignment(LAMMPS *lmp, Fix *owner, const char *fast, Buffer layers,
                                 bool chooses) :
    Pointers(lmp),
    fix(owner), fast_group(fast), buffer(layers), finebit(0), clockbit(0), dynamic(false),
    fast_auto(chooses),
    file_dynamic(false), saved_buffer{-1, 0.0}, saved_clock{-1.0, -1.0}, fast_seen{-1.0, -1.0},
    reverse_flags(nullptr)
{
  const int ifast = group->find(fast_group);
  if (ifast < 0)
    error->all(FLERR, "Fix pe_jump/async fast group {} does not exist{}", fast_group, errorurl(57));
  finebit = clockbit = group->bitmask[ifast];    // own clock group: see find_groups()
  dynamic = group->dynamic[ifast] != 0;
}

/* ---------------------------------------------------------------------- */

void ClockAssignment::warn_if_made_static()
{
  if (file_dynamic && !dynamic && (comm->me == 0))
    error->warning(
        FLERR,
        "Fix pe_jump/async: the fast group {} was dynamic when the restart file was written, "
        "and read_restart restored it as static{}",
        fast_group, errorurl(63));
  file_dynamic = false;
}

/* ----------------------------------------------------------------------
   with buffer layers, or a dynamic fast group (whose atoms change at any
   step, while atoms change clock at coarse nodes only), the fine clock is
   a group of the fix's own
------------------------------------------------------------------------- */

bool ClockAssignment::own_group() const
{
  return (buffer.layers > 0) || dynamic || fast_auto;
}

/* ---------------------------------------------------------------------- */

void ClockAssignment::create_clock_group()
{
  if (own_group()) group->find_or_create((std::string(fix->id) + "_fine_clock").c_str());
}

/* ---------------------------------------------------------------------- */

void ClockAssignment::delete_clock_group() const
{
  if (!group || !modify || !output || !own_group()) return;
  const std::string name = std::string(fix->id) + "_fine_clock";
  const int igroup = group->find(name);
  if (igroup <= 0) return;
  for (const auto *ifix : modify->get_fix_list())
    if (ifix->igroup == igroup) return;
  for (const auto *icompute : modify->get_compute_list())
    if (icompute->igroup == igroup) return;
  for (const auto *idump : output->get_dump_list())
    if (idump->igroup == igroup) return;
  if ((atom->firstgroupname && (name == atom->firstgroupname)) ||
      (neighbor->includegroup == igroup))
    return;
  group->assign(name + " delete");
}

/* ----------------------------------------------------------------------
   the fast group (and the fine-clock group of the buffer), looked up again
   at every init: a deleted group's bit may have gone to another group
   since. The fast group must be a non-empty part of the fix group.
------------------------------------------------------------------------- */

void ClockAssignment::find_groups()
{
  const int ifast = group->find(fast_group);
  if (ifast < 0)
    error->all(FLERR, "Fix pe_jump/async: its fast group {} was deleted{}", fast_group,
               errorurl(58));
  finebit = group->bitmask[ifast];
  clockbit = finebit;
  if ((group->dynamic[ifast] != 0) != dynamic)
    error->all(FLERR,
               "Fix pe_jump/async: its fast group {} was made {} after the fix was defined{}",
               fast_group, dynamic ? "static" : "dynamic", errorurl(60));
  if (own_group()) {
    const std::string clock_group = std::string(fix->id) + "_fine_clock";
    const int iclock = group->find(clock_group);
    if (iclock < 0)
      error->all(FLERR, "Fix pe_jump/async: its fine-clock group {} was deleted{}", clock_group,
                 errorurl(59));
    clockbit = group->bitmask[iclock];
  }

  const int *mask = atom->mask;
  bigint local[2] = {0, 0};    // fast atoms in the fix group, fast atoms outside it
  for (int i = 0; i < atom->nlocal; i++) {
    if (!(mask[i] & finebit)) continue;
    if (mask[i] & fix->groupbit)
      ++local[0];
    else
      ++local[1];
  }
  // a dynamic group is brought up to date after init (and may be empty);
  // its atoms outside the fix group stay on the coarse clock. With fast
  // auto the group may be empty too
  if (dynamic) return;
  bigint global[2];
  MPI_Allreduce(local, global, 2, MPI_LMP_BIGINT, MPI_SUM, world);
  if (global[1] > 0)
    error->all(FLERR, "Fix pe_jump/async: {} atoms of the fast group are not in the fix group {}{}",
               global[1], group->names[fix->igroup], errorurl(61));
  if ((global[0] == 0) && !fast_auto)
    error->all(FLERR, "Fix pe_jump/async: the fast group has no atoms in the fix group{}",
               errorurl(62));
}

/* ----------------------------------------------------------------------
   buffer keyword: the fine clock takes the fast group and, layer by layer,
   the atoms of the fix group that share an interaction (a bonded one, or a
   pair of the neighbor lists) with an atom on the fine clock. The slow
   partners of the interface then move on the fine clock with it, which
   keeps the period-2 mode of the slow interface atoms out of resonance
   with the fast region.
------------------------------------------------------------------------- */

bool ClockAssignment::assign_buffer(bool started, InteractionSplit &split)
{
  // a static fast group redefined between runs: atoms of it that are not
  // on the fine clock (atoms that left it stay on the fine clock, as
  // buffer atoms would; a dynamic group or fast auto is followed at
  // coarse nodes)
  const bool grown = !dynamic && !fast_auto && started && (fast_off_clock() > 0);
  const bool redo = own_group() && (!started || (buffer != saved_buffer) || grown);
  saved_buffer = buffer;
  if (!redo) return false;
  assign(split);
  return true;
}

/* ----------------------------------------------------------------------
   the fine clock: the atoms of the fast group in the fix group, and the
   buffer layers
------------------------------------------------------------------------- */

void ClockAssignment::assign(InteractionSplit &split, const std::vector<int> *chosen)
{
  int *mask = atom->mask;
  for (int i = 0; i < atom->nlocal; i++) {
    if (((mask[i] & finebit) || (chosen && (*chosen)[i])) && (mask[i] & fix->groupbit))
      mask[i] |= clockbit;
    else
      mask[i] &= ~clockbit;
  }
  comm->forward_comm(fix);
  fast_signature(fast_seen, chosen);
  // each layer adds the slow partners of the fine clock; stop early when a
  // layer adds no atom (everything reachable is on the fine clock)
  for (int layer = 0; layer < buffer.layers; layer++) {
    split.build();
    // the partners at the current positions, whatever the age of the lists
    split.mark_fine_partners(participant, buffer.reach);
    gather(participant);
    int added = 0;
    for (int i = 0; i < atom->nlocal; i++)
      if (participant[i] && (mask[i] & fix->groupbit) && !(mask[i] & clockbit)) {
        mask[i] |= clockbit;
        added = 1;
      }
    comm->forward_comm(fix);
    int any = 0;
    MPI_Allreduce(&added, &any, 1, MPI_INT, MPI_MAX, world);
    if (!any) break;
  }
  // the layers split the interactions for the clocks of the layers before
  split.invalidate();
}

/* ----------------------------------------------------------------------
   true if LAMMPS updated the dynamic fast group (every nevery steps) in
   the coarse step that ends at step node (steps fine steps)
------------------------------------------------------------------------- */

bool ClockAssignment::updated_in(bigint node, int steps) const
{
  const Fix *criterion = dynamic ? modify->get_fix_by_id("GROUP_" + fast_group) : nullptr;
  if (!criterion) return false;
  const bigint every = criterion->nevery;
  const auto updates = [every](bigint step) {    // updates of the group up to step
    return (step >= 0) ? step / every : -((every - 1 - step) / every);
  };
  return updates(node) != updates(node - steps);
}

/* ----------------------------------------------------------------------
   at the end of the coarse step that ends at step node, every atom at its
   node: a dynamic fast group updated in that coarse step is evaluated
   again, on the state that output at the node shows. LAMMPS' own
   updates, during the force computation, see the atoms
   inside a step, and the per-atom energies of the fine interactions only.
   Here the criterion sees the positions (ghost atoms' too: unless
   ghosts_at_node, the node is not written and they are still where the
   last fine step's force evaluation left them), velocities, time and (on
   steps that tally them, where the fix evaluates everything at the node)
   per-atom energies of the node; output at the node shows this group, and
   the clocks follow it
------------------------------------------------------------------------- */

void ClockAssignment::evaluate_at_node(bigint node, int steps, bool ghosts_at_node)
{
  if (!updated_in(node, steps)) return;
  if (!ghosts_at_node) comm->forward_comm();
  modify->get_fix_by_id("GROUP_" + fast_group)->setup(0);
}

/* ----------------------------------------------------------------------
   at the coarse node of step node (the one before it steps earlier): true
   if a dynamic fast group updated in the coarse step (and evaluated at
   its end, evaluate_at_node()) or the atoms chosen by the fix differ from
   those of the last assignment (global)
------------------------------------------------------------------------- */

bool ClockAssignment::due(const std::vector<int> *chosen, bigint node, int steps)
{
  if (!dynamic && !fast_auto) return false;
  ++changes.tally[Changes::NODES];
  if (!updated_in(node, steps) && !fast_auto) return false;
  double now[2];
  fast_signature(now, chosen);
  return (now[0] != fast_seen[0]) || (now[1] != fast_seen[1]);
}

/* ----------------------------------------------------------------------
   after due(): the new assignment; to_fine[i] (owned atoms) tells the atoms
   that changed clock (1: to the fine clock, -1: to the coarse clock).
   Returns true if any atom changed clock (global).
------------------------------------------------------------------------- */

bool ClockAssignment::follow(InteractionSplit &split, std::vector<int> &to_fine,
                             const std::vector<int> *chosen)
{
  const int *mask = atom->mask;
  const int nlocal = atom->nlocal;
  to_fine.assign(nlocal, 0);
  for (int i = 0; i < nlocal; i++) to_fine[i] = (mask[i] & clockbit) ? 1 : 0;
  assign(split, chosen);
  bigint local = 0;
  for (int i = 0; i < nlocal; i++) {
    const int fine = (mask[i] & clockbit) ? 1 : 0;
    to_fine[i] = fine - to_fine[i];
    if (to_fine[i]) ++local;
  }
  bigint moved = 0;
  MPI_Allreduce(&local, &moved, 1, MPI_LMP_BIGINT, MPI_SUM, world);
  changes.tally[Changes::ATOMS] += moved;
  if (moved) ++changes.tally[Changes::CHANGED];
  changed();    // the state of the atoms is carried over: it fits this fine clock
  return moved != 0;
}

/* ----------------------------------------------------------------------
   the clock changes of the run, in the log: the coarse nodes of the run at
   which the clocks were decided (a change at the last node of a run is
   decided as the next one begins)
------------------------------------------------------------------------- */

void ClockAssignment::report(const char *style)
{
  const bigint *tally = changes.tally;
  if (follows_group() && (comm->me == 0))
    utils::logmesg(lmp, "Fix {}: {} atoms changed clock at {} of {} coarse nodes\n", style,
                   tally[Changes::ATOMS], tally[Changes::CHANGED], tally[Changes::NODES]);
  // the next run counts anew (one with "pre no" has no setup); the
  // pseudo-energy they changed adds up over the runs
  for (bigint &n : changes.tally) n = 0;
}

/* ----------------------------------------------------------------------
   atoms that flicker between the clocks add up what their restarted jumps
   change: at a coarse step the slow dynamics cannot resolve (its jumps
   large against the velocities) they pump the energy up while every
   atom's step stays small, where the stability guard sees nothing
------------------------------------------------------------------------- */

void ClockAssignment::add_change_energy(double dh, const std::function<double()> &kinetic,
                                        const char *style)
{
  changes.energy += dh;
  if (changes.kinetic < 0.0) changes.kinetic = kinetic();
  const double added = fabs(changes.energy);
  const double level = changes.warned ? CHANGE_ENERGY_STOP : CHANGE_ENERGY_WARN;
  if (added <= level * changes.kinetic) return;
  const double scale = MAX(changes.kinetic, kinetic());
  // (a group at rest has nothing to compare with)
  if ((scale <= 0.0) || (added <= CHANGE_ENERGY_WARN * scale)) return;
  const std::string what =
      fmt::format("Fix {}: by step {} the clock changes since the fix was defined have changed the "
                  "pseudo-energy by {:.8g}, {:.3g} % of the kinetic energy of the group ({:.8g})",
                  style, update->ntimestep, changes.energy, 100.0 * added / scale, scale);
  if (added > CHANGE_ENERGY_STOP * scale)
    error->all(FLERR, "{}; the fix stops where this exceeds {} %{}", what,
               100.0 * CHANGE_ENERGY_STOP, errorurl(64));
  if (changes.warned) return;
  changes.warned = true;
  if (comm->me == 0) error->warning(FLERR, what + errorurl(64));
}

/* ----------------------------------------------------------------------
   atoms of the fast group in the fix group that are not on the fine clock
   (global)
------------------------------------------------------------------------- */

bigint ClockAssignment::fast_off_clock() const
{
  const int *mask = atom->mask;
  bigint local = 0, all = 0;
  for (int i = 0; i < atom->nlocal; i++)
    if ((mask[i] & finebit) && (mask[i] & fix->groupbit) && !(mask[i] & clockbit)) ++local;
  MPI_Allreduce(&local, &all, 1, MPI_LMP_BIGINT, MPI_SUM, world);
  return all;
}

/* ----------------------------------------------------------------------
   a set of atoms is told by its number and the sum of the hashes of the
   IDs, summed modulo 2^64, so that the sum does not depend on the order
   and two sets collide with a chance of about 2^-53 (a plain sum of IDs
   cannot tell 10 + 13 from 11 + 12)
------------------------------------------------------------------------- */

namespace {
template <typename In> void id_signature(const Atom *atom, MPI_Comm world, In in, double *sig)
{
  unsigned long long count = 0, sum = 0;
  for (int i = 0; i < atom->nlocal; i++)
    if (in(i)) {
      ++count;
      sum += id_hash(atom->tag[i]);
    }
  // (summed as the counts and the 32-bit halves of the sums, which a
  // signed 64-bit sum holds for any number of ranks: LAMMPS' serial MPI
  // stubs have no unsigned 64-bit type)
  long long local[3] = {static_cast<long long>(count), static_cast<long long>(sum >> 32),
                        static_cast<long long>(sum & 0xffffffffULL)};
  long long all[3];
  MPI_Allreduce(local, all, 3, MPI_LONG_LONG, MPI_SUM, world);
  const unsigned long long total =
      (static_cast<unsigned long long>(all[1]) << 32) + static_cast<unsigned long long>(all[2]);
  sig[0] = static_cast<double>(all[0]);
  sig[1] = static_cast<double>(total >> 11);    // 53 bits: exact in a double
}
}    // namespace

/* ----------------------------------------------------------------------
   fast auto TOL (jump: the jumps [v]^n, nfine: K): at a coarse node, the
   atoms of the fix group that would move by more than TOL times the
   neighbor skin over a coarse step on the
   coarse clock, h_S |v^n + (h_S/h) [v]^n/2| with h their present step (the
   free flight of their next step with the jump fitted to the coarse
   step), go on the fine clock; those on it stay while they would move by
   more than half that (no flapping between the clocks)
------------------------------------------------------------------------- */

void ClockAssignment::choose_fast(double tol, double coarse, int nfine, double **jump,
                                  std::vector<int> &chosen) const
{
  const int nlocal = atom->nlocal;
  const int *mask = atom->mask;
  const int *on_coarse = slow();
  double **v = atom->v;
  const double limit = tol * neighbor->skin;
  chosen.assign(nlocal, 0);
  for (int i = 0; i < nlocal; i++) {
    if (!(mask[i] & fix->groupbit)) continue;
    const double ratio = on_coarse[i] ? 1.0 : static_cast<double>(nfine);
    double d2 = 0.0;
    for (int k = 0; k < 3; k++) {
      const double u = v[i][k] + 0.5 * ratio * jump[i][k];
      d2 += u * u;
    }
    const double d = coarse * sqrt(d2);
    chosen[i] = (d > limit) || (!on_coarse[i] && (d > 0.5 * limit));
  }
}

/* ----------------------------------------------------------------------
   the atoms of the fast group in the fix group (and those chosen)
------------------------------------------------------------------------- */

void ClockAssignment::fast_signature(double *sig, const std::vector<int> *chosen) const
{
  const int *mask = atom->mask;
  id_signature(
      atom, world,
      [&](int i) {
        return ((mask[i] & finebit) || (chosen && (*chosen)[i])) && (mask[i] & fix->groupbit);
      },
      sig);
}

/* ---------------------------------------------------------------------- */

bool ClockAssignment::changed()
{
  const int *mask = atom->mask;
  double clock[2];
  id_signature(
      atom, world,
      [&](int i) {
        return (mask[i] & fix->groupbit) && (mask[i] & clockbit);
      },
      clock);
  const bool differ = (clock[0] != saved_clock[0]) || (clock[1] != saved_clock[1]);
  saved_clock[0] = clock[0];
  saved_clock[1] = clock[1];
  return differ;
}

/* ---------------------------------------------------------------------- */

void ClockAssignment::find_slow(const InteractionSplit &split)
{
  const int *mask = atom->mask;
  const int nlocal = atom->nlocal;
  slow_flag.resize(nlocal);
  slow_atoms.clear();
  for (int i = 0; i < nlocal; i++) {
    slow_flag[i] = split.coarse(i);
    if (slow_flag[i] && (mask[i] & fix->groupbit)) slow_atoms.push_back(i);
  }
}

/* ----------------------------------------------------------------------
   atoms that move on fine steps: those on the fine clock and the slow ones
   that take part in a fine interaction, here or as a ghost elsewhere (the
   lists are built where every atom is at the same time)
------------------------------------------------------------------------- */

void ClockAssignment::find_moving(const InteractionSplit &split)
{
  split.mark_fine_participants(participant);
  gather(participant);

  const int *mask = atom->mask;
  const int nlocal = atom->nlocal;
  moving_flag.resize(nlocal);
  moving_atoms.clear();
  fast_atoms.clear();
  slow_moving.clear();
  slow_held.clear();
  for (int i = 0; i < nlocal; i++) {
    moving_flag[i] = !slow_flag[i] || participant[i];
    if (!(mask[i] & fix->groupbit)) continue;
    if (moving_flag[i]) {
      moving_atoms.push_back(i);
      (slow_flag[i] ? slow_moving : fast_atoms).push_back(i);
    } else {
      slow_held.push_back(i);
    }
  }
}

/* ---------------------------------------------------------------------- */

void ClockAssignment::save(double *list, double *seen, double *reach) const
{
  list[0] = saved_buffer.layers;
  *reach = saved_buffer.reach;
  list[1] = saved_clock[0];
  list[2] = saved_clock[1];
  seen[0] = fast_seen[0];
  seen[1] = fast_seen[1];
}

/* ---------------------------------------------------------------------- */

void ClockAssignment::restore(const double *list, const double *seen, const double *reach)
{
  saved_buffer = {static_cast<int>(list[0]), reach ? *reach : 0.0};
  saved_clock[0] = list[1];
  saved_clock[1] = list[2];
  fast_seen[0] = seen[0];
  fast_seen[1] = seen[1];
}

/* ---------------------------------------------------------------------- */

void ClockAssignment::gather(std::vector<int> &flags)
{
  reverse_flags = &flags;
  comm->reverse_comm(fix, 1);
  reverse_flags = nullptr;
}

/* ---------------------------------------------------------------------- */

int ClockAssignment::pack_forward(int n, const int *list, double *buf) const
{
  const int *mask = atom->mask;
  for (int i = 0; i < n; i++) buf[i] = (mask[list[i]] & clockbit) ? 1.0 : 0.0;
  return n;
}

/* ---------------------------------------------------------------------- */

void ClockAssignment::unpack_forward(int n, int first, const double *buf)
{
  int *mask = atom->mask;
  for (int i = 0; i < n; i++) {
    if (buf[i] != 0.0)
      mask[first + i] |= clockbit;
    else
      mask[first + i] &= ~clockbit;
  }
}

/* ---------------------------------------------------------------------- */

int ClockAssignment::pack_reverse(int n, int first, double *buf) const
{
  for (int i = 0; i < n; i++) buf[i] = (*reverse_flags)[first + i];
  return n;
}

/* ---------------------------------------------------------------------- */

void ClockAssignment::unpack_reverse(int n, const int *list, const double *buf)
{
  for (int i = 0; i < n; i++)
    if (buf[i] != 0.0) (*reverse_flags)[list[i]] = 1;
}

/* ---------------------------------------------------------------------- */

ClockClasses::ClockClasses(LAMMPS *lmp, AtomState &table) :
    Pointers(lmp), state(table), counts{0.0, 0.0, 0.0}
{
  class_field = state.add("klass", 1, OUTSIDE);
}

/* ----------------------------------------------------------------------
   slow = on the coarse clock; mixed = fine-clock atom that shares an
   interaction with a slow atom; fast = the other fine-clock atoms
------------------------------------------------------------------------- */

void ClockClasses::label(const InteractionSplit &split, ClockAssignment &assign, int groupbit)
{
  split.mark_interface(interface_flag);
  assign.gather(interface_flag);

  const int *mask = atom->mask;
  const int nlocal = atom->nlocal;
  double *klass = state.val(class_field);
  double local[3] = {0.0, 0.0, 0.0};
  for (int i = 0; i < nlocal; i++) {
    if (!(mask[i] & groupbit))
      klass[i] = OUTSIDE;
    else if (split.coarse(i))
      klass[i] = SLOW;
    else
      klass[i] = interface_flag[i] ? MIXED : FAST;
    if (klass[i] != OUTSIDE) local[static_cast<int>(klass[i])] += 1.0;
  }
  MPI_Allreduce(local, counts, 3, MPI_DOUBLE, MPI_SUM, world);
}

/* ---------------------------------------------------------------------- */

double *ClockClasses::classes() const
{
  return state.val(class_field);
}
