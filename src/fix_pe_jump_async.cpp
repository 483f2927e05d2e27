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

/* ----------------------------------------------------------------------
   Asynchronous (slow/mixed/fast) version of the pseudo-energy conserving
   scheme, section 4 of: F. Marazzato, A. Ern, C. Mariotti, L. Monasse,
   Comput. Methods Appl. Mech. Engrg. 347 (2019) 906-927.

   Every LAMMPS time step is a fine step h_F. Atoms of the fast group move
   and jump on every fine step with the forces of the FINE interactions
   (those involving a fast-group atom). Slow atoms move in free flight over
   the coarse step h_S = K h_F; the fine interactions they take part in
   (mixed-slow) are integrated over each fine step and summed, the COARSE
   interactions (slow-slow) are integrated once per coarse step at the
   coarse quadrature nodes, and the slow atoms jump at the coarse nodes.
------------------------------------------------------------------------- */

#include "fix_pe_jump_async.h"

#include "atom.h"
#include "bond.h"
#include "comm.h"
#include "error.h"
#include "force.h"
#include "group.h"
#include "memory.h"
#include "modify.h"
#include "neighbor.h"
#include "output.h"
#include "pair.h"
#include "pe_jump_async_clocks.h"
#include "pe_jump_atom_state.h"
#include "pe_jump_force_sampler.h"
#include "pe_jump_interaction_split.h"
#include "pe_jump_node_sampler.h"
#include "pe_jump_other_fixes.h"
#include "pe_jump_quadrature.h"
#include "pe_jump_stability_guard.h"
#include "pe_jump_step_control.h"
#include "pe_jump_two_step.h"
#include "update.h"

#include <cmath>
#include <cstring>

using namespace LAMMPS_NS;
using namespace FixConst;
using PEJump::AsyncClocks;
using PEJump::AtomState;
using PEJump::ForceSampler;
using PEJump::InteractionSplit;
using PEJump::NodeSampler;
using PEJump::OtherFixes;
using PEJump::StabilityGuard;

static constexpr int NASYNC_GLOBAL = 6;    // K, fine step index, elapsed time, buffer, clock

/* ---------------------------------------------------------------------- */

FixPEJumpAsync::FixPEJumpAsync(LAMMPS *lmp, int narg, char **arg) :
    FixPEJump(lmp, narg, arg, 5, true), finebit(0), clockbit(0), reverse_flags(nullptr),
    split_calls(-1), topology_at_setup(0), changes_seen(0), saved_buffer(-1), split(nullptr),
    clocks(nullptr), fcoarse(nullptr), nmax_coarse(0)
{
  if (narg < 5) utils::missing_cmd_args(FLERR, "fix pe_jump/async", error);
  const int nfine = utils::inumeric(FLERR, arg[3], false, lmp);
  if (nfine < 1) error->all(FLERR, "Fix pe_jump/async needs K >= 1 fine steps per coarse step");
  const int ifast = group->find(arg[4]);
  if (ifast < 0) error->all(FLERR, "Fix pe_jump/async fast group {} does not exist", arg[4]);
  finebit = group->bitmask[ifast];
  fast_group = arg[4];

  if (steps->adapts())
    error->all(FLERR,
               "Fix pe_jump/async does not support the adapt keyword: the coarse and fine "
               "steps are fixed (use fix pe_jump for adaptive steps)");
  if (automatic)
    error->all(FLERR, "Fix pe_jump/async does not support quadrature auto: choose a fixed rule");
  if (steps->keeps_history())
    error->all(FLERR, "Fix pe_jump/async does not support compensate yes: its steps are fixed");
  if (opts.damp_time >= 0.0)
    error->all(FLERR, "Fix pe_jump/async does not support the damp keyword yet");
  if (opts.sample_mask != ForceSampler::ALL)
    error->all(FLERR,
               "Fix pe_jump/async samples all force contributions: remove the sample keyword");

  counts[0] = counts[1] = counts[2] = 0.0;
  saved_clock[0] = saved_clock[1] = -1.0;
  stats_slow[0] = stats_slow[1] = 0.0;
  clockbit = finebit;    // with buffer layers: see post_constructor()
  comm_forward = 1;
  split = new InteractionSplit(lmp, groupbit, clockbit);

  size_vector = 9;
  delete[] extlist;
  extlist = new int[size_vector]{1, 1, 0, 0, 0, 0, 0, 0, 0};
  peratom_flag = 1;
  size_peratom_cols = 0;
  peratom_freq = 1;

  FACC = state->add("facc", 3, 0.0);
  FSTART_COARSE = rule->has_end_nodes() ? state->add("fstart_coarse", 3, 0.0) : -1;
  KLASS = state->add("klass", 1, OUTSIDE);
  clocks = new AsyncClocks(lmp, *state, nfine);
  for (int i = 0; i < atom->nlocal; i++) FixPEJumpAsync::set_arrays(i);
  atom->add_callback(Atom::GROW);
  atom->add_callback(Atom::RESTART);
}

/* ----------------------------------------------------------------------
   with buffer layers the fine clock is a group of its own, kept with the
   atoms (and in restart files); init() looks it up
------------------------------------------------------------------------- */

void FixPEJumpAsync::post_constructor()
{
  FixPEJump::post_constructor();
  if (opts.buffer_layers > 0) group->find_or_create((std::string(id) + "_fine_clock").c_str());
}

/* ---------------------------------------------------------------------- */

FixPEJumpAsync::~FixPEJumpAsync()
{
  delete clocks;
  delete split;
  memory->destroy(fcoarse);
}

/* ---------------------------------------------------------------------- */

int FixPEJumpAsync::setmask()
{
  return FixPEJump::setmask() | POST_NEIGHBOR | PRE_FORCE;
}

/* ---------------------------------------------------------------------- */

void FixPEJumpAsync::init()
{
  FixPEJump::init();
  refuse_unsplittable();
  refuse_other_fixes();
  topology_at_setup = topology_count();
  find_groups();
  split->set_fine_bit(clockbit);
  maxexchange = state->values();
}

/* ----------------------------------------------------------------------
   force fields that cannot be split into fine and coarse interactions
------------------------------------------------------------------------- */

void FixPEJumpAsync::refuse_unsplittable() const
{
  if (force->pair && force->pair->manybody_flag)
    error->all(FLERR,
               "Fix pe_jump/async cannot split the many-body pair style {} into slow and fast "
               "interactions: use fix pe_jump",
               force->pair_style);
  if (force->kspace)
    error->all(FLERR,
               "Fix pe_jump/async cannot split k-space ({}) into slow and fast interactions: "
               "use fix pe_jump",
               force->kspace_style);
  if (atom->peri_flag)
    error->all(FLERR,
               "Fix pe_jump/async cannot split peridynamic interactions (atom style {}): their "
               "bonds are kept in partner lists of the pair style, not in the neighbor lists. Use "
               "fix pe_jump",
               atom->atom_style);
  // a bond style whose bonds can break (partial_flag) changes the topology
  // and may keep data per entry of the bond list, whose order the split
  // changes
  if (force->bond && force->bond->partial_flag && (atom->molecular != Atom::ATOMIC))
    error->all(FLERR,
               "Fix pe_jump/async cannot split bond style {}: its bonds can break, and the split "
               "reorders the bond list. Use fix pe_jump",
               force->bond_style);
}

/* ----------------------------------------------------------------------
   other fixes that integrate atoms or act on the forces
------------------------------------------------------------------------- */

void FixPEJumpAsync::refuse_other_fixes() const
{
  // the interactions among atoms outside the fix group are evaluated only
  // at coarse nodes, for the slow atoms: nothing else may integrate them
  for (const auto &ifix : modify->get_fix_list())
    if ((ifix != this) && ifix->time_integrate)
      error->all(FLERR,
                 "Fix pe_jump/async must be the only time integration fix (found fix {} {}): "
                 "atoms outside its group are frozen scenery",
                 ifix->id, ifix->style);

  // the fine and coarse forces of a slow atom are sampled apart, so another
  // fix cannot act on its total force; only fix enforce2d (which zeroes a
  // component that is zero anyway) may act on the forces
  for (const auto &ifix : modify->get_fix_list())
    if ((ifix != this) && (ifix->setmask() & POST_FORCE) &&
        !utils::strmatch(ifix->style, "^enforce2d"))
      error->all(FLERR,
                 "Fix pe_jump/async cannot yet be combined with fix {} ({}), which acts on the "
                 "forces: a slow atom's fine and coarse forces are sampled apart. Hold atoms by "
                 "leaving them out of the fix group (frozen scenery), or use fix pe_jump",
                 ifix->id, ifix->style);
}

/* ----------------------------------------------------------------------
   the fast group (and the fine-clock group of the buffer), looked up again
   at every init: a deleted group's bit may have gone to another group
   since. The fast group must be a non-empty part of the fix group.
------------------------------------------------------------------------- */

void FixPEJumpAsync::find_groups()
{
  const int ifast = group->find(fast_group);
  if (ifast < 0) error->all(FLERR, "Fix pe_jump/async: its fast group {} was deleted", fast_group);
  finebit = group->bitmask[ifast];
  clockbit = finebit;
  if (opts.buffer_layers > 0) {
    const std::string clock_group = std::string(id) + "_fine_clock";
    const int iclock = group->find(clock_group);
    if (iclock < 0)
      error->all(FLERR, "Fix pe_jump/async: its fine-clock group {} was deleted", clock_group);
    clockbit = group->bitmask[iclock];
  }

  const int *mask = atom->mask;
  bigint local[2] = {0, 0};    // fast atoms in the fix group, fast atoms outside it
  for (int i = 0; i < atom->nlocal; i++) {
    if (!(mask[i] & finebit)) continue;
    if (mask[i] & groupbit)
      ++local[0];
    else
      ++local[1];
  }
  bigint global[2];
  MPI_Allreduce(local, global, 2, MPI_LMP_BIGINT, MPI_SUM, world);
  if (global[1] > 0)
    error->all(FLERR, "Fix pe_jump/async: {} atoms of the fast group are not in the fix group {}",
               global[1], group->names[igroup]);
  if (global[0] == 0)
    error->all(FLERR, "Fix pe_jump/async: the fast group has no atoms in the fix group");
}

/* ---------------------------------------------------------------------- */

void FixPEJumpAsync::setup_post_neighbor()
{
  post_neighbor();
}

/* ----------------------------------------------------------------------
   buffer keyword, when the scheme starts: the fine clock takes the fast
   group and, layer by layer, the atoms of the fix group that share an
   interaction (a bonded one, or a pair of the neighbor lists) with an atom
   on the fine clock. The slow partners of the interface then move on the
   fine clock with it, which keeps the period-2 mode of the slow interface
   atoms out of resonance with the fast region.
------------------------------------------------------------------------- */

void FixPEJumpAsync::assign_buffer()
{
  int *mask = atom->mask;
  const int nall = atom->nlocal + atom->nghost;
  for (int i = 0; i < nall; i++) {
    if (mask[i] & finebit)
      mask[i] |= clockbit;
    else
      mask[i] &= ~clockbit;
  }
  // each layer adds the slow partners of the fine clock; stop early when a
  // layer adds no atom (everything reachable is on the fine clock)
  for (int layer = 0; layer < opts.buffer_layers; layer++) {
    split->build();
    split->mark_fine_participants(participant);
    gather_flags(participant);
    int added = 0;
    for (int i = 0; i < atom->nlocal; i++)
      if (participant[i] && (mask[i] & groupbit) && !(mask[i] & clockbit)) {
        mask[i] |= clockbit;
        added = 1;
      }
    comm->forward_comm(this);
    int any = 0;
    MPI_Allreduce(&added, &any, 1, MPI_INT, MPI_MAX, world);
    if (!any) break;
  }
  split_calls = -1;    // split the lists again for the new clocks
}

/* ----------------------------------------------------------------------
   fix pe_jump takes a velocity that another fix changed as an impulse;
   here a slow atom has no node velocity inside a coarse step, so such
   changes are refused. The atoms on the fine clock are checked every fine
   step (before their steps begin, and before they jump), all atoms at
   coarse nodes, where the ranks agree on the outcome.
------------------------------------------------------------------------- */

void FixPEJumpAsync::node_impulses()
{
  if (!watch(OtherFixes::BETWEEN_STEPS | OtherFixes::INSIDE_STEP)) return;
  if (watch(OtherFixes::BETWEEN_STEPS))
    note_velocity_changes(clocks->at_coarse_node() ? nullptr : &fast_atoms);
  if (!clocks->at_coarse_node()) return;
  int any = 0;
  MPI_Allreduce(&changes_seen, &any, 1, MPI_INT, MPI_MAX, world);
  if (any)
    error->all(FLERR,
               "Fix pe_jump/async: another fix (a thermostat, fix momentum, fix wall/reflect, "
               "...) changed velocities during the run before step {}; pe_jump/async does not "
               "take velocity changes yet. Use fix pe_jump",
               update->ntimestep);
}

/* ---------------------------------------------------------------------- */

void FixPEJumpAsync::note_velocity_changes(const AtomList *only)
{
  double **v = atom->v;
  const double *vsig = scheme->vsig();
  for_atoms(only, [&](int i) {
    if (PEJump::velocity_fingerprint(v[i]) != vsig[i]) changes_seen = 1;
  });
}

/* ----------------------------------------------------------------------
   the fine steps of the atoms on the fine clock begin (a slow atom's
   free-flight velocity is its node velocity plus half its jump)
------------------------------------------------------------------------- */

void FixPEJumpAsync::open_steps()
{
  double **v = atom->v;
  double **jump = scheme->jump();
  double *vsig = watch(OtherFixes::INSIDE_STEP) ? scheme->vsig() : nullptr;
  for (const int i : fast_atoms) {
    for (int k = 0; k < 3; k++) v[i][k] += 0.5 * jump[i][k];
    if (vsig) vsig[i] = PEJump::velocity_fingerprint(v[i]);
  }
}

/* ----------------------------------------------------------------------
   the atoms on the fine clock are inside their fine step; the slow atoms
   keep their node velocity over the coarse step
------------------------------------------------------------------------- */

PEJump::FreeFlight FixPEJumpAsync::free_flight() const
{
  return {atom->v, scheme->jump(), slow.data()};
}

/* ----------------------------------------------------------------------
   the steps that begin are those of the atoms on the fine clock only
------------------------------------------------------------------------- */

bool FixPEJumpAsync::open_while_moving() const
{
  return false;
}

/* ----------------------------------------------------------------------
   number of bonds, angles, dihedrals and impropers of the system
------------------------------------------------------------------------- */

bigint FixPEJumpAsync::topology_count() const
{
  if (atom->molecular == Atom::ATOMIC) return 0;
  return atom->nbonds + atom->nangles + atom->ndihedrals + atom->nimpropers;
}

/* ----------------------------------------------------------------------
   the lists were rebuilt: split them again (the clocks of the atoms never
   change, so the split does not depend on when it is done)
------------------------------------------------------------------------- */

void FixPEJumpAsync::post_neighbor()
{
  // the classes of the interactions hold for the whole run: the topology
  // must not change (fix bond/create, bond/break, ...)
  if (topology_count() != topology_at_setup)
    error->all(FLERR,
               "Fix pe_jump/async: the bonds, angles, dihedrals or impropers changed during the "
               "run (from {} to {}), e.g. by a fix that creates or breaks bonds: the "
               "interaction split cannot follow. Use fix pe_jump",
               topology_at_setup, topology_count());
  split->build();
  split_calls = neighbor->ncalls;
  find_slow();    // atoms are reordered only when the lists are rebuilt
  find_moving();
}

/* ----------------------------------------------------------------------
   atoms that move on fine steps: those on the fine clock and the slow ones
   that take part in a fine interaction, here or as a ghost elsewhere. A
   slow atom that joins a fine interaction inside a coarse step catches up
   with its free flight first (and the ghosts are updated).
------------------------------------------------------------------------- */

void FixPEJumpAsync::find_moving()
{
  split->mark_fine_participants(participant);
  gather_flags(participant);

  const int *mask = atom->mask;
  const int nlocal = atom->nlocal;
  moving.resize(nlocal);
  moving_atoms.clear();
  fast_atoms.clear();
  slow_moving.clear();
  int caught = 0;
  for (int i = 0; i < nlocal; i++) {
    moving[i] = !slow[i] || participant[i];
    if (!(mask[i] & groupbit)) continue;
    if (moving[i]) {
      moving_atoms.push_back(i);
      (slow[i] ? slow_moving : fast_atoms).push_back(i);
      if (clocks->times()[i] != AsyncClocks::MOVING) {
        clocks->catch_up(i, free_flight(), true);
        caught = 1;
      }
    } else {
      clocks->hold(i);    // stays here until it is needed
    }
  }
  int any = 0;
  MPI_Allreduce(&caught, &any, 1, MPI_INT, MPI_MAX, world);
  if (any) comm->forward_comm();
}

/* ----------------------------------------------------------------------
   largest |v|^2 and |[v]|^2 of the local slow atoms (they change only at
   coarse nodes)
------------------------------------------------------------------------- */

void FixPEJumpAsync::slow_magnitudes()
{
  stats_slow[0] = stats_slow[1] = 0.0;
  double **v = atom->v;
  double **jump = scheme->jump();
  for (const int i : slow_atoms) {
    double vv = 0.0, jj = 0.0;
    for (int k = 0; k < 3; k++) {
      const double vhalf = v[i][k] + 0.5 * jump[i][k];
      vv += vhalf * vhalf;
      jj += jump[i][k] * jump[i][k];
    }
    stats_slow[0] = MAX(stats_slow[0], vv);
    stats_slow[1] = MAX(stats_slow[1], jj);
  }
}

/* ---------------------------------------------------------------------- */

/* ---------------------------------------------------------------------- */

void FixPEJumpAsync::catch_up_all()
{
  clocks->catch_up_all(free_flight(), moving.data());
}

/* ----------------------------------------------------------------------
   free flight to the primary node: the moving atoms every fine step, all
   atoms of the group (the interior slow ones from where they stopped) at
   the last fine step of a coarse step
------------------------------------------------------------------------- */

void FixPEJumpAsync::advance(double t)
{
  double **x = atom->x;
  const PEJump::FreeFlight vhalf = free_flight();
  clocks->moving_at(t);
  if (!clocks->last_fine_step()) {
    for (const int i : moving_atoms)
      for (int k = 0; k < 3; k++) x[i][k] += t * vhalf(i, k);
    return;
  }
  const int *mask = atom->mask;
  const int nlocal = atom->nlocal;
  double *tpos = clocks->times();
  for (int i = 0; i < nlocal; i++) {
    if (!(mask[i] & groupbit)) continue;
    const double dt = (tpos[i] == AsyncClocks::MOVING) ? t : clocks->now() - tpos[i];
    for (int k = 0; k < 3; k++) x[i][k] += dt * vhalf(i, k);
    tpos[i] = AsyncClocks::MOVING;
  }
}

/* ---------------------------------------------------------------------- */

void FixPEJumpAsync::setup(int vflag)
{
  started = scheme->agree_on_started(started, group_atoms(), style);
  // the buffer is assigned when the scheme starts, or again if the restart
  // file was written with other buffer layers
  state->ensure(atom->nlocal);
  if ((opts.buffer_layers > 0) && (!started || (opts.buffer_layers != saved_buffer)))
    assign_buffer();
  // a run with "pre no" keeps the lists of the previous run: split them if
  // this fix has not seen them yet
  if (split_calls != neighbor->ncalls) post_neighbor();
  if (!split->pair_stays_in_lists())
    error->all(FLERR,
               "Fix pe_jump/async cannot split pair style {}: it computes forces that are not in "
               "its neighbor lists (e.g. from partner lists of its own). Use fix pe_jump",
               force->pair_style);
  // start nodes of slow atoms inside a coarse step cannot be taken again:
  // new atoms take theirs at their first evaluation
  fresh_atoms = 0;
  changes_seen = 0;
  check_clocks();
  FixPEJump::setup(vflag);
  saved_buffer = opts.buffer_layers;
  slow_magnitudes();
  comm->forward_comm();    // the scheme's start may have caught up interior slow atoms
  label_classes();
}

/* ----------------------------------------------------------------------
   a new start of the two-step scheme also starts a new coarse step
------------------------------------------------------------------------- */

void FixPEJumpAsync::start_scheme(const char *why, bool with_start)
{
  catch_up_all();
  if (with_start) {
    clocks->begin_coarse();
    double **facc = state->vec(FACC);
    for (int i = 0; i < atom->nlocal; i++)
      for (int k = 0; k < 3; k++) facc[i][k] = 0.0;
  }
  FixPEJump::start_scheme(why, with_start);
}

/* ---------------------------------------------------------------------- */

double FixPEJumpAsync::kick_step(int i) const
{
  return split->coarse(i) ? clocks->steps() * update->dt : update->dt;
}

/* ----------------------------------------------------------------------
   inside a coarse step the slow atoms have no node velocity to reverse
------------------------------------------------------------------------- */

bool FixPEJumpAsync::can_reverse() const
{
  return clocks->at_coarse_node();
}

/* ---------------------------------------------------------------------- */

std::string FixPEJumpAsync::instability_advice() const
{
  return fmt::format("The fine step {} (fast and mixed atoms), the coarse step {} (slow atoms), or "
                     "their coupling at the interface, which has resonances (see the stability "
                     "section of the fix pe_jump/async documentation), is unstable: reduce the "
                     "time step or change K{}",
                     h_step, clocks->steps() * h_step,
                     opts.buffer_layers ? ""
                                        : ", or add the keyword buffer 1 (the slow partners of "
                                          "the interface then take the fine step)");
}

/* ----------------------------------------------------------------------
   Lobatto start nodes at q^0: the fine interactions for every atom, the
   slow interactions for the slow atoms
------------------------------------------------------------------------- */

void FixPEJumpAsync::store_start_node()
{
  double **f = atom->f;
  double **fstart = scheme->fstart();
  double **fstart_coarse = state->vec(FSTART_COARSE);
  const int *mask = atom->mask;
  const int nlocal = atom->nlocal;
  NodeSampler::Keep keep(*nodes);

  split->activate(InteractionSplit::FINE);
  sampler->compute(ForceSampler::ALL, 0, 0);
  for (int i = 0; i < nlocal; i++)
    if (mask[i] & groupbit)
      for (int k = 0; k < 3; k++) fstart[i][k] = f[i][k];

  split->activate(InteractionSplit::COARSE);
  sampler->compute(ForceSampler::ALL, 0, 0);
  for (int i = 0; i < nlocal; i++)
    for (int k = 0; k < 3; k++) fstart_coarse[i][k] = split->coarse(i) ? f[i][k] : 0.0;

  split->restore();
}

/* ---------------------------------------------------------------------- */

double FixPEJumpAsync::node_cost()
{
  const auto which = split->active();
  return ((which == InteractionSplit::NONE) || (which == InteractionSplit::ALL))
      ? 1.0
      : split->fraction(which);
}

/* ----------------------------------------------------------------------
   the Verlet loop evaluates the fine interactions only
------------------------------------------------------------------------- */

void FixPEJumpAsync::pre_force(int /*vflag*/)
{
  split->activate(InteractionSplit::FINE);
}

/* ---------------------------------------------------------------------- */

void FixPEJumpAsync::pre_reverse(int eflag, int vflag)
{
  split->restore();
  FixPEJump::pre_reverse(eflag, vflag);
}

/* ---------------------------------------------------------------------- */

void FixPEJumpAsync::find_slow()
{
  const int *mask = atom->mask;
  const int nlocal = atom->nlocal;
  slow.resize(nlocal);
  slow_atoms.clear();
  for (int i = 0; i < nlocal; i++) {
    slow[i] = split->coarse(i);
    if (slow[i] && (mask[i] & groupbit)) slow_atoms.push_back(i);
  }
}

/* ----------------------------------------------------------------------
   fine nodes for every atom; on the last fine step of a coarse step also
   the coarse nodes q_S^n + c H v_S of the slow atoms, H the coarse step,
   measured from the current position q_S^n + elapsed v_S
------------------------------------------------------------------------- */

void FixPEJumpAsync::check_lists()
{
  const int first = rule->has_end_nodes() ? 1 : 0;
  const double c_lo = rule->node[first];
  const bool tally = tally_step();
  const double c_hi = tally ? 1.0 : rule->node.back();
  const double coarse_step = clocks->steps() * h_step;
  const bool coarse_end = clocks->last_fine_step();
  double **xhold = neighbor->dist_check ? neighbor->get_xhold() : nullptr;
  double local[StabilityGuard::NMEASURES] = {0.0, 0.0, 0.0, 0.0, 0.0};
  if (!coarse_end && guard->has_stats()) {
    // the magnitudes were taken per clock by final_integrate(); the fine
    // nodes' excursions matter only for the atoms that move to them, and
    // not at all if the Verlet loop checks the only node
    const double hf2 = h_step * h_step, hs2 = coarse_step * coarse_step;
    local[1] = MAX(hf2 * guard->speed2(), hs2 * stats_slow[0]);
    local[2] = MAX(hf2 * guard->jump2(), hs2 * stats_slow[1]);
    local[3] = MAX(guard->jump2(), stats_slow[1]);
    local[4] = MAX(guard->speed2(), stats_slow[0]);
    if (xhold && (tally || (rule->size() > 1)))
      local[0] = guard->excursion(group_atoms(&moving_atoms), free_flight(), xhold, c_lo * h_step,
                                  c_hi * h_step);
    finish_check(local);
    return;
  }
  const double cp = rule->node[rule->primary()] * h_step;
  StabilityGuard::Nodes at{h_step, c_lo * h_step, c_hi * h_step, cp,     slow.data(),
                           0.0,    0.0,           coarse_step,   nullptr};
  if (coarse_end) {
    // the coarse nodes q_S^n + c H v_S of the slow atoms, measured from
    // their current positions q_S^n + elapsed v_S (less their lag)
    const double elapsed = clocks->start(), span = elapsed + h_step;
    const double *tpos = clocks->times();
    const int nlocal = atom->nlocal;
    lag.resize(nlocal);
    for (int i = 0; i < nlocal; i++)
      lag[i] = (tpos[i] == AsyncClocks::MOVING) ? 0.0 : elapsed - tpos[i];
    at.lo2 = c_lo * span - elapsed;
    at.hi2 = rule->node.back() * span - elapsed;
    at.lag = lag.data();
  }
  guard->measure(group_atoms(), free_flight(), scheme->jump(), xhold, at, local);
  finish_check(local);
}

/* ----------------------------------------------------------------------
   fcoarse = sum_k w_k F_slow(q_S^n + c_k H v_S) for the slow atoms, from
   the positions of the primary fine node; the Lobatto start node is the end
   node of the previous coarse step
------------------------------------------------------------------------- */

void FixPEJumpAsync::coarse_quadrature_sum(double coarse_step)
{
  const int reuse_start = rule->has_end_nodes();
  double **fstart_coarse = reuse_start ? state->vec(FSTART_COARSE) : nullptr;
  for (const int i : slow_atoms) {
    for (int k = 0; k < 3; k++)
      fcoarse[i][k] = reuse_start ? rule->weight[0] * fstart_coarse[i][k] : 0.0;
  }
  const double at = clocks->start() + rule->node[rule->primary()] * h_step;
  split->activate(InteractionSplit::COARSE);
  const int evaluated =
      nodes->sum_nodes(*rule, reuse_start ? 1 : 0, -1, coarse_step, -at, free_flight(),
                       group_atoms(&slow_atoms), opts.sample_mask, fcoarse, fstart_coarse);
  evals_step += evaluated * node_cost();
  split->restore();
}

/* ----------------------------------------------------------------------
   forces of the fine interactions at the primary fine node are known:
   sample the other fine nodes, on the last fine step the coarse nodes, then
   jump (fast and mixed atoms every fine step, slow atoms at coarse nodes)
   and move on to the end of the fine step
------------------------------------------------------------------------- */

void FixPEJumpAsync::final_integrate()
{
  if (watch(OtherFixes::INSIDE_STEP)) note_velocity_changes(&fast_atoms);
  grow_work();
  if (nmax_coarse < atom->nmax) {
    nmax_coarse = atom->nmax;
    memory->destroy(fcoarse);
    memory->create(fcoarse, nmax_coarse, 3, "pe_jump/async:fcoarse");
  }
  const bool coarse_end = clocks->last_fine_step();

  // with a single node, evaluated by the Verlet loop with nothing else to
  // separate, the forces there are the fine quadrature average itself
  evals_step = split->fraction(InteractionSplit::FINE);
  const bool direct = (rule->size() == 1) && !split_primary();
  if (!direct) {
    split->activate(InteractionSplit::FINE);
    quadrature_sum(&moving_atoms);
    split->restore();
  }
  if (coarse_end) coarse_quadrature_sum(clocks->start() + h_step);

  // per clock: largest |v|^2, |[v]|^2 (the slow atoms' change at coarse nodes)
  double mag[2][2] = {{0.0, 0.0}, {0.0, 0.0}};
  double **favg = direct ? atom->f : fsum;
  if (coarse_end)
    reach_coarse_node(favg, mag);
  else
    continue_fine_step(favg, mag[0]);
  guard->set_stats(mag[0][0], mag[0][1]);

  // interior slow atoms catch up wherever their positions are looked at:
  // output, other fixes at the end of the step, the end of the run
  clocks->end_fine(h_step);
  if (!coarse_end && others->step_observed()) catch_up_all();

  split->activate(InteractionSplit::ALL);
  tally_at_node();
  split->restore();
  evals_total += evals_step;
  scheme->forget_energies();

  // the labels are output only: take them where something looks, when
  // tally_at_node() has brought the ghosts to the node
  if (coarse_end && (eflag_step || vflag_step || others->step_observed())) label_classes();
}

/* ----------------------------------------------------------------------
   the last fine step of a coarse step: every atom reaches the coarse node
   (the interior slow atoms from where they stopped), the atoms on the fine
   clock jump with favg, the slow ones with the sums of their fine forces
   over the coarse step and the coarse quadrature sum
------------------------------------------------------------------------- */

void FixPEJumpAsync::reach_coarse_node(double **favg, double mag[2][2])
{
  double **x = atom->x;
  double **v = atom->v;
  double **f = atom->f;
  double **jump = scheme->jump();
  double **facc = state->vec(FACC);
  double **fstart = scheme->fstart();
  double *tpos = clocks->times();
  const PEJump::FreeFlight vhalf = free_flight();
  double *vsig = watch(OtherFixes::BETWEEN_STEPS) ? scheme->vsig() : nullptr;
  const double rest = (1.0 - rule->node[rule->primary()]) * h_step;
  const double coarse_step = clocks->start() + h_step;
  const auto one = [&](int i) {
    const double dt = (tpos[i] == AsyncClocks::MOVING) ? rest : coarse_step - tpos[i];
    for (int k = 0; k < 3; k++) x[i][k] += dt * vhalf(i, k);
    if (fstart)
      for (int k = 0; k < 3; k++) fstart[i][k] = fsample[i][k];
    // interior slow atoms have no fine interactions: only other fixes' forces
    const double *fa = moving[i] ? favg[i] : f[i];
    if (!slow[i]) {
      scheme->jump_atom(i, h_step, fa, mag[0]);
    } else {
      double fslow[3];
      for (int k = 0; k < 3; k++) {
        fslow[k] = (facc[i][k] + h_step * fa[k]) / coarse_step + fcoarse[i][k];
        facc[i][k] = 0.0;
      }
      for (int k = 0; k < 3; k++) v[i][k] += 0.5 * jump[i][k];    // into its step
      scheme->jump_atom(i, coarse_step, fslow, mag[1]);
    }
    if (vsig) vsig[i] = PEJump::velocity_fingerprint(v[i]);
    tpos[i] = moving[i] ? AsyncClocks::MOVING : 0.0;    // at the next coarse step's start
  };
  for_atoms(nullptr, one);
  for (int k = 0; k < 2; k++)
    stats_slow[k] = std::isfinite(mag[1][k]) ? mag[1][k] : StabilityGuard::BLOWUP;
}

/* ----------------------------------------------------------------------
   inside a coarse step: the atoms on the fine clock take a synchronous
   step; of the slow atoms those in a fine interaction move on, and they
   (and the others, if other fixes add forces) collect the fine forces
------------------------------------------------------------------------- */

void FixPEJumpAsync::continue_fine_step(double **favg, double *mag)
{
  double **x = atom->x;
  double **f = atom->f;
  double **facc = state->vec(FACC);
  double **fstart = scheme->fstart();
  const PEJump::FreeFlight vhalf = free_flight();
  const double rest = (1.0 - rule->node[rule->primary()]) * h_step;
  finish_step(&fast_atoms, favg, rest, mag);
  for (const int i : slow_moving)
    for (int k = 0; k < 3; k++) x[i][k] += rest * vhalf(i, k);
  // forces on interior slow atoms come only from fixes that add forces
  // (fix enforce2d, the only other one allowed, zeroes a zero component)
  for (const int i : others->add_forces() ? slow_atoms : slow_moving) {
    const double *fa = moving[i] ? favg[i] : f[i];
    for (int k = 0; k < 3; k++) {
      if (fstart) fstart[i][k] = fsample[i][k];
      facc[i][k] += h_step * fa[k];
    }
  }
}

/* ----------------------------------------------------------------------
   at a coarse node, with the ghosts at the node: slow = on the coarse
   clock; mixed = fine-clock atom that shares an interaction with a slow
   atom; fast = the other fine-clock atoms. Also the global counts of the
   three classes.
------------------------------------------------------------------------- */

void FixPEJumpAsync::label_classes()
{
  split->mark_interface(interface_flag);
  gather_flags(interface_flag);

  const int *mask = atom->mask;
  const int nlocal = atom->nlocal;
  double *klass = state->val(KLASS);
  double local[3] = {0.0, 0.0, 0.0};
  for (int i = 0; i < nlocal; i++) {
    if (!(mask[i] & groupbit))
      klass[i] = OUTSIDE;
    else if (split->coarse(i))
      klass[i] = SLOW;
    else
      klass[i] = interface_flag[i] ? MIXED : FAST;
    if (klass[i] != OUTSIDE) local[static_cast<int>(klass[i])] += 1.0;
  }
  MPI_Allreduce(local, counts, 3, MPI_DOUBLE, MPI_SUM, world);
}

/* ----------------------------------------------------------------------
   flags set on ghost atoms are set on their owners too
------------------------------------------------------------------------- */

void FixPEJumpAsync::gather_flags(std::vector<int> &flags)
{
  reverse_flags = &flags;
  comm->reverse_comm(this, 1);
  reverse_flags = nullptr;
}

/* ----------------------------------------------------------------------
   the fine clock of the ghost atoms, after assign_buffer()
------------------------------------------------------------------------- */

int FixPEJumpAsync::pack_forward_comm(int n, int *list, double *buf, int /*pbc_flag*/,
                                      int * /*pbc*/)
{
  const int *mask = atom->mask;
  for (int i = 0; i < n; i++) buf[i] = (mask[list[i]] & clockbit) ? 1.0 : 0.0;
  return n;
}

/* ---------------------------------------------------------------------- */

void FixPEJumpAsync::unpack_forward_comm(int n, int first, double *buf)
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

int FixPEJumpAsync::pack_reverse_comm(int n, int first, double *buf)
{
  if (!reverse_flags) return FixPEJump::pack_reverse_comm(n, first, buf);
  for (int i = 0; i < n; i++) buf[i] = (*reverse_flags)[first + i];
  return n;
}

/* ---------------------------------------------------------------------- */

void FixPEJumpAsync::unpack_reverse_comm(int n, int *list, double *buf)
{
  if (!reverse_flags) {
    FixPEJump::unpack_reverse_comm(n, list, buf);
    return;
  }
  for (int i = 0; i < n; i++)
    if (buf[i] != 0.0) (*reverse_flags)[list[i]] = 1;
}

/* ---------------------------------------------------------------------- */

double FixPEJumpAsync::compute_vector(int n)
{
  switch (n) {
    case 5:
      return clocks->at_coarse_node() ? 1.0 : 0.0;
    case 6:
    case 7:
    case 8:
      return counts[n - 6];
  }
  return FixPEJump::compute_vector(n);
}

/* ----------------------------------------------------------------------
   the per-atom output (the classes) is a field of the state table, which
   may move when it grows
------------------------------------------------------------------------- */

void FixPEJumpAsync::show_classes()
{
  vector_atom = state->val(KLASS);
}

/* ---------------------------------------------------------------------- */

void FixPEJumpAsync::grow_arrays(int nmax)
{
  FixPEJump::grow_arrays(nmax);
  show_classes();
}

/* ---------------------------------------------------------------------- */

void FixPEJumpAsync::copy_arrays(int i, int j, int delflag)
{
  FixPEJump::copy_arrays(i, j, delflag);
  show_classes();
}

/* ---------------------------------------------------------------------- */

void FixPEJumpAsync::set_arrays(int i)
{
  FixPEJump::set_arrays(i);
  show_classes();
}

/* ---------------------------------------------------------------------- */

int FixPEJumpAsync::unpack_exchange(int nlocal, double *buf)
{
  const int m = FixPEJump::unpack_exchange(nlocal, buf);
  show_classes();
  return m;
}

/* ---------------------------------------------------------------------- */

void FixPEJumpAsync::unpack_restart(int nlocal, int nth)
{
  FixPEJump::unpack_restart(nlocal, nth);
  show_classes();
}

/* ----------------------------------------------------------------------
   global state: that of fix pe_jump, K, the position inside the coarse step
------------------------------------------------------------------------- */

void FixPEJumpAsync::write_restart(FILE *fp)
{
  double list[NGLOBAL + NASYNC_GLOBAL];
  global_state(list);
  clocks->save(&list[NGLOBAL]);
  list[NGLOBAL + 3] = saved_buffer;
  list[NGLOBAL + 4] = saved_clock[0];
  list[NGLOBAL + 5] = saved_clock[1];
  if (comm->me == 0) {
    int size = sizeof(list);
    fwrite(&size, sizeof(int), 1, fp);
    fwrite(list, sizeof(double), NGLOBAL + NASYNC_GLOBAL, fp);
  }
}

/* ---------------------------------------------------------------------- */

void FixPEJumpAsync::restart(char *buf)
{
  FixPEJump::restart(buf);
  auto *list = reinterpret_cast<double *>(buf);
  if (!clocks->restore(&list[NGLOBAL])) {
    if (started && (comm->me == 0))
      utils::logmesg(lmp,
                     "Fix {}: K differs from the restart file: the two-step scheme restarts "
                     "from the current state\n",
                     style);
    started = 0;
    return;
  }
  saved_buffer = static_cast<int>(list[NGLOBAL + 3]);
  saved_clock[0] = list[NGLOBAL + 4];
  saved_clock[1] = list[NGLOBAL + 5];
}

/* ----------------------------------------------------------------------
   which atoms are on the fine clock (their number and the sum of their
   IDs): if that changed since the last run (the fast group redefined, a
   restart with another fast group or buffer), the two-step state of the
   atoms that changed clock no longer fits. At a coarse node the scheme
   restarts; inside a coarse step the slow atoms have no node state, so
   the change is refused.
------------------------------------------------------------------------- */

void FixPEJumpAsync::check_clocks()
{
  double local[2] = {0.0, 0.0}, clock[2];
  const int *mask = atom->mask;
  const tagint *tag = atom->tag;
  for (int i = 0; i < atom->nlocal; i++)
    if ((mask[i] & groupbit) && (mask[i] & clockbit)) {
      local[0] += 1.0;
      local[1] += static_cast<double>(tag[i]);
    }
  MPI_Allreduce(local, clock, 2, MPI_DOUBLE, MPI_SUM, world);
  const bool changed = (clock[0] != saved_clock[0]) || (clock[1] != saved_clock[1]);
  saved_clock[0] = clock[0];
  saved_clock[1] = clock[1];
  if (!started || !changed) return;
  if (!clocks->at_coarse_node())
    error->all(FLERR,
               "Fix pe_jump/async: the atoms on the fine clock changed inside a coarse step "
               "({} of {} fine steps done): change the fast group, or the buffer, only at a "
               "coarse node (after a multiple of K steps)",
               clocks->done(), clocks->steps());
  if (comm->me == 0)
    utils::logmesg(lmp,
                   "Fix {}: the atoms on the fine clock changed since the last run: restarting "
                   "the two-step scheme at this coarse node\n",
                   style);
  started = 0;
}

/* ---------------------------------------------------------------------- */

double FixPEJumpAsync::memory_usage()
{
  return FixPEJump::memory_usage() + static_cast<double>(nmax_coarse) * 3 * sizeof(double);
}
