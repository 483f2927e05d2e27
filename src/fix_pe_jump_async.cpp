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
#include "domain.h"
#include "dump.h"
#include "error.h"
#include "force.h"
#include "group.h"
#include "input.h"
#include "modify.h"
#include "neighbor.h"
#include "output.h"
#include "pair.h"
#include "pe_jump_async_clocks.h"
#include "pe_jump_atom_state.h"
#include "pe_jump_clock_assignment.h"
#include "pe_jump_first_group.h"
#include "pe_jump_force_sampler.h"
#include "pe_jump_interaction_split.h"
#include "pe_jump_node_sampler.h"
#include "pe_jump_other_fixes.h"
#include "pe_jump_quadrature.h"
#include "pe_jump_stability_guard.h"
#include "pe_jump_two_step.h"
#include "pe_jump_work_forces.h"
#include "timer.h"
#include "update.h"

#include <cmath>
#include <cstring>

using namespace LAMMPS_NS;
using namespace FixConst;
using PEJump::AsyncClocks;
using PEJump::AtomState;
using PEJump::ClockAssignment;
using PEJump::FirstGroup;
using PEJump::ForceSampler;
using PEJump::InteractionSplit;
using PEJump::NodeSampler;
using PEJump::OtherFixes;
using PEJump::Quadrature;
using PEJump::StabilityGuard;

/* ---------------------------------------------------------------------- */

FixPEJumpAsync::FixPEJumpAsync(LAMMPS *lmp, int narg, char **arg) :
    Fix(lmp, narg, arg), rule(nullptr), sampler(nullptr), nodes(nullptr), state(nullptr),
    scheme(nullptr), guard(nullptr), others(nullptr), split(nullptr), clocks(nullptr),
    assign(nullptr), classes(nullptr), work(nullptr), first(nullptr), reinit_pending(0),
    opened_ahead(0), build_ahead(0.0), changes_seen(0)
{
  if (narg < 5) utils::missing_cmd_args(FLERR, "fix pe_jump/async", error);
  opts.parse(lmp, style, narg, arg, 5, true);
  const int nfine = utils::inumeric(FLERR, arg[3], false, lmp);
  if (nfine < 1) error->all(FLERR, "Fix pe_jump/async needs K >= 1 fine steps per coarse step");
  if (group->dynamic[igroup])
    error->all(FLERR,
               "Fix pe_jump/async does not allow a dynamic fix group ({}): the fast group may "
               "be dynamic, the fix group must not",
               group->names[igroup]);
  if (group->find(arg[4]) < 0)
    error->all(FLERR, "Fix pe_jump/async fast group {} does not exist", arg[4]);
  refuse_keywords();

  rule = new Quadrature(static_cast<Quadrature::Family>(opts.family), opts.npoints);
  sampler = new ForceSampler(lmp);
  nodes = new NodeSampler(lmp, sampler);
  guard = new StabilityGuard(lmp);
  others = new OtherFixes(lmp, this);
  work = new PEJump::WorkForces(lmp, 3);
  state = new AtomState(lmp);
  scheme = new PEJump::TwoStep(lmp, *state, rule->has_end_nodes());
  FACC = state->add("facc", 3, 0.0);
  FSTART_COARSE = rule->has_end_nodes() ? state->add("fstart_coarse", 3, 0.0) : -1;
  assign = new ClockAssignment(lmp, this, arg[4], {opts.buffer_layers, opts.buffer_reach},
                               opts.fast_auto > 0.0);
  classes = new PEJump::ClockClasses(lmp, *state);
  clocks = new AsyncClocks(lmp, *state, nfine);
  split = new InteractionSplit(lmp, groupbit, assign->clock_bit());
  first = new FirstGroup(lmp);

  time_integrate = 1;
  scalar_flag = 1;
  vector_flag = 1;
  size_vector = 9;
  global_freq = 1;
  extscalar = 1;
  extvector = -1;
  extlist = new int[size_vector]{1, 1, 0, 0, 0, 0, 0, 0, 0};
  peratom_flag = 1;
  size_peratom_cols = 0;
  peratom_freq = 1;
  restart_global = 1;
  restart_peratom = 1;
  create_attribute = 1;
  comm_forward = 1;
  comm_reverse = 1;
  force_reneighbor = 1;
  next_reneighbor = -1;

  for (int i = 0; i < atom->nlocal; i++) FixPEJumpAsync::set_arrays(i);
  atom->add_callback(Atom::GROW);
  atom->add_callback(Atom::RESTART);
}

/* ----------------------------------------------------------------------
   keywords of fix pe_jump that the fixed steps of the two clocks exclude
------------------------------------------------------------------------- */

void FixPEJumpAsync::refuse_keywords() const
{
  if (opts.adapt_eps > 0.0)
    error->all(FLERR,
               "Fix pe_jump/async does not support the adapt keyword: the coarse and fine "
               "steps are fixed (use fix pe_jump for adaptive steps)");
  if (opts.auto_tol > 0.0)
    error->all(FLERR, "Fix pe_jump/async does not support quadrature auto: choose a fixed rule");
  if (opts.compensate > 0)
    error->all(FLERR, "Fix pe_jump/async does not support compensate yes: its steps are fixed");
  if (opts.damp_time >= 0.0)
    error->all(FLERR, "Fix pe_jump/async does not support the damp keyword yet");
  if (opts.sample_mask != ForceSampler::ALL)
    error->all(FLERR,
               "Fix pe_jump/async samples all force contributions: remove the sample keyword");
}

/* ----------------------------------------------------------------------
   with buffer layers the fine clock is a group of its own, kept with the
   atoms (and in restart files); init() looks it up
------------------------------------------------------------------------- */

void FixPEJumpAsync::post_constructor()
{
  assign->create_clock_group();
}

/* ---------------------------------------------------------------------- */

FixPEJumpAsync::~FixPEJumpAsync()
{
  if (modify->get_fix_by_id(id)) {
    // removed inside a coarse step (unfix): whatever integrates the atoms
    // next starts from the velocities, which must hold the fine impulses
    // (not when LAMMPS is torn down: update and force are gone then)
    if (update && force && !clocks->at_coarse_node())
      hand_over_impulses(fmt::format("fix {} is removed", id));
    atom->delete_callback(id, Atom::GROW);
    atom->delete_callback(id, Atom::RESTART);
  }
  if (assign) assign->delete_clock_group();
  delete[] extlist;
  delete first;
  delete split;
  delete clocks;
  delete classes;
  delete assign;
  delete scheme;
  delete state;
  delete work;
  delete others;
  delete guard;
  delete nodes;
  delete sampler;
  delete rule;
}

/* ---------------------------------------------------------------------- */

int FixPEJumpAsync::setmask()
{
  return INITIAL_INTEGRATE | POST_NEIGHBOR | PRE_FORCE | PRE_REVERSE | FINAL_INTEGRATE;
}

/* ---------------------------------------------------------------------- */

void FixPEJumpAsync::init()
{
  scheme->init(style);
  guard->refuse_zero_skin(style, false, "the coarse clock");
  others->sort(*sampler);
  sampler->refuse_velocity_forces(style, rule->name(), false);
  refuse_unsplittable();
  refuse_other_fixes();
  nodes->refuse_step_end_side_effects(
      style,
      "on steps that tally energy or virial or dump forces this fix evaluates the fine "
      "interactions at their primary node and every interaction at the step end");
  first->refuse_unsupported(style);
  if (first->active() && assign->follows_group())
    error->all(FLERR,
               "Fix pe_jump/async cannot {} with neigh_modify include: atoms would change "
               "clock outside the include group",
               (opts.fast_auto > 0.0)
                   ? std::string("choose fine-clock atoms with fast auto")
                   : "follow the dynamic fast group " + assign->fast_group_name());
  split->start_run();
  assign->find_groups();
  split->set_fine_bit(assign->clock_bit());
  maxexchange = state->values();
  // write_data initializes the system first (also with nofix)
  if (input->command && (strcmp(input->command, "write_data") == 0)) refuse_data_file();
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

  // a force field that changes during the run (fix adapt) would be sampled
  // at the fine and the coarse nodes at other times than theirs; fixes that
  // act in initial_integrate (fix recenter, fix tmd) take the atoms for
  // being at the step end, where neither clock leaves them
  for (const auto &ifix : modify->get_fix_list()) {
    const bool adapts = utils::strmatch(ifix->style, "^adapt");
    if ((ifix != this) && !ifix->time_integrate &&
        (adapts || (ifix->setmask() & INITIAL_INTEGRATE)))
      error->all(FLERR,
                 "Fix pe_jump/async cannot yet be combined with fix {} ({}), which {}. Use fix "
                 "pe_jump",
                 ifix->id, ifix->style,
                 adapts ? "changes the force field during the run: the fine and the coarse forces "
                          "are sampled at different times"
                        : "acts on the atoms in initial_integrate, where they are inside their "
                          "steps on two clocks");
  }
  // fix deform with remap v changes the velocity of an atom that crosses a
  // periodic boundary, which a slow atom cannot take inside its step
  if (domain->deform_vremap)
    error->all(FLERR,
               "Fix pe_jump/async cannot yet be combined with fix deform with remap v, which "
               "changes the velocities of atoms that cross a periodic boundary. Use remap x, or "
               "fix pe_jump");

  // the fine and coarse forces of a slow atom are sampled apart, so another
  // fix cannot act on its total force; only fix enforce2d (which zeroes a
  // component that is zero anyway) may act on the forces. The advice fits
  // what the fix is for: atoms held by setforce and its kin can be left
  // out of the fix group, an indenter or an added force cannot
  for (const auto &ifix : modify->get_fix_list()) {
    if ((ifix == this) || !(ifix->setmask() & POST_FORCE) ||
        utils::strmatch(ifix->style, "^enforce2d"))
      continue;
    if (OtherFixes::replaces_forces(ifix))
      error->all(FLERR,
                 "Fix pe_jump/async cannot yet be combined with fix {} ({}), which acts on the "
                 "forces: a slow atom's fine and coarse forces are sampled apart. Hold atoms by "
                 "leaving them out of the fix group (frozen scenery), or use fix pe_jump",
                 ifix->id, ifix->style);
    if (utils::strmatch(ifix->style, "^indent"))
      error->all(FLERR,
                 "Fix pe_jump/async cannot yet be combined with fix {} ({}): the indenter pushes "
                 "atoms with a force that depends on their positions, which the split into fine "
                 "and coarse forces (sampled at different nodes for a slow atom) cannot place. "
                 "Use fix pe_jump, which takes the indenter's force as an impulse in every step",
                 ifix->id, ifix->style);
    error->all(FLERR,
               "Fix pe_jump/async cannot yet be combined with fix {} ({}), which adds forces: "
               "the split into fine and coarse forces (sampled at different nodes for a slow "
               "atom) cannot place them. Use fix pe_jump, which takes such forces as impulses",
               ifix->id, ifix->style);
  }

  // the velocity changes of fixes made for them would be refused at their
  // first action (refuse_velocity_changes()), which may come late in the
  // run (fix momentum 100: step 101)
  for (const auto &ifix : modify->get_fix_list())
    if ((ifix != this) && OtherFixes::changes_velocities(ifix))
      error->all(FLERR,
                 "Fix pe_jump/async cannot yet be combined with fix {} ({}), which changes "
                 "velocities during the run: pe_jump/async does not take velocity changes yet. "
                 "Use fix pe_jump",
                 ifix->id, ifix->style);
}

/* ---------------------------------------------------------------------- */

void FixPEJumpAsync::setup_post_neighbor()
{
  post_neighbor();
}

/* ----------------------------------------------------------------------
   fix pe_jump takes a velocity that another fix changed as an impulse;
   here a slow atom has no node velocity inside a coarse step, so such
   changes are refused. The atoms on the fine clock are checked every fine
   step (before their steps begin, and before they jump), all atoms at the
   last fine step of a coarse step and at coarse nodes, where the ranks
   agree on the outcome (and at the end of a run).
------------------------------------------------------------------------- */

void FixPEJumpAsync::node_impulses()
{
  if (!watch(OtherFixes::BETWEEN_STEPS | OtherFixes::INSIDE_STEP)) return;
  if (watch(OtherFixes::BETWEEN_STEPS))
    note_velocity_changes(clocks->at_coarse_node() ? nullptr : &assign->fast_atoms);
  if (clocks->at_coarse_node()) refuse_velocity_changes();
}

/* ----------------------------------------------------------------------
   the ranks agree whether another fix changed a velocity (global)
------------------------------------------------------------------------- */

void FixPEJumpAsync::refuse_velocity_changes()
{
  int any = 0;
  MPI_Allreduce(&changes_seen, &any, 1, MPI_INT, MPI_MAX, world);
  if (any)
    error->all(FLERR,
               "Fix pe_jump/async: another fix (fix wall/reflect, fix oneway, ...) changed "
               "velocities during the run before step {}; pe_jump/async does not take velocity "
               "changes yet. Use fix pe_jump",
               update->ntimestep);
}

/* ---------------------------------------------------------------------- */

void FixPEJumpAsync::note_velocity_changes(const AtomList *only)
{
  if (scheme->any_changed(group_atoms(only))) changes_seen = 1;
}

/* ----------------------------------------------------------------------
   the fine steps of the atoms on the fine clock begin (a slow atom's
   free-flight velocity is its node velocity plus half its jump)
------------------------------------------------------------------------- */

void FixPEJumpAsync::open_steps()
{
  scheme->open(group_atoms(&assign->fast_atoms), watch(OtherFixes::INSIDE_STEP));
}

/* ----------------------------------------------------------------------
   the atoms on the fine clock are inside their fine step; the slow atoms
   keep their node velocity over the coarse step
------------------------------------------------------------------------- */

PEJump::FreeFlight FixPEJumpAsync::free_flight() const
{
  return {atom->v, scheme->jump(), assign->slow()};
}

/* ----------------------------------------------------------------------
   the lists were rebuilt: split them again (the clocks of the atoms never
   change, so the split does not depend on when it is done)
------------------------------------------------------------------------- */

void FixPEJumpAsync::post_neighbor()
{
  split->check_topology();
  first->keep_build_positions();
  split->build();
  // atoms are reordered only when the lists are rebuilt
  assign->find_slow(*split);
  // (before find_moving() holds the slow atoms that sit out at their time)
  if (build_ahead != 0.0) back_from_build();
  if (assign->find_moving(*split, *clocks, free_flight())) comm->forward_comm();
  first->find_partners(assign->participants(), assign->moving(), groupbit);
}

/* ----------------------------------------------------------------------
   largest |v|^2 and |[v]|^2 of the local slow atoms (they change only at
   coarse nodes)
------------------------------------------------------------------------- */

void FixPEJumpAsync::slow_magnitudes()
{
  double **v = atom->v;
  double **jump = scheme->jump();
  double most[2] = {0.0, 0.0};
  for (const int i : assign->slow_atoms) {
    double vv = 0.0, jj = 0.0;
    for (int k = 0; k < 3; k++) {
      const double vhalf = v[i][k] + 0.5 * jump[i][k];
      vv += vhalf * vhalf;
      jj += jump[i][k] * jump[i][k];
    }
    most[0] = MAX(most[0], vv);
    most[1] = MAX(most[1], jj);
  }
  guard->set_slow_stats(most[0], most[1]);
}

/* ---------------------------------------------------------------------- */

void FixPEJumpAsync::catch_up_all()
{
  clocks->catch_up_all(free_flight(), assign->moving());
  first->held_atoms_moved();
}

/* ----------------------------------------------------------------------
   free flight to the primary node of a fine step inside a coarse step:
   the atoms that move on fine steps
------------------------------------------------------------------------- */

void FixPEJumpAsync::advance(double t)
{
  double **x = atom->x;
  const PEJump::FreeFlight vhalf = free_flight();
  clocks->moving_at(t);
  if (!opened_ahead)
    for (const int i : assign->moving_atoms)
      for (int k = 0; k < 3; k++) x[i][k] += t * vhalf(i, k);
  // with neigh_modify include, LAMMPS checks the distances of the atoms of
  // the include group only
  if (first->moved_too_far(groupbit, false, guard->all_within()))
    next_reneighbor = update->ntimestep;
}

/* ----------------------------------------------------------------------
   the last fine step of a coarse step: every atom of the group moves to
   its primary node (the interior slow ones from where they stopped, a lag
   behind), in the same pass as the stability guard measures the fine
   nodes and, for the slow atoms, the coarse nodes q_S^n + c H v_S, H the
   coarse step, from the positions before the move
------------------------------------------------------------------------- */

void FixPEJumpAsync::all_to_primary_node(double t)
{
  const double h_step = update->dt;    // the fine step
  const int first_node = rule->has_end_nodes() ? 1 : 0;
  const double c_lo = rule->node[first_node];
  const double elapsed = clocks->start(), span = elapsed + h_step;
  guard->step(h_step);
  // (none of the atoms can be beyond half the skin: no distances to measure)
  const bool within = guard->all_within();
  double **xhold = (neighbor->dist_check && !within) ? neighbor->get_xhold() : nullptr;
  const StabilityGuard::Nodes at{h_step,
                                 c_lo * h_step,
                                 (nodes->step_end_evaluated() ? 1.0 : rule->node.back()) * h_step,
                                 t,
                                 assign->slow(),
                                 c_lo * span - elapsed,
                                 rule->node.back() * span - elapsed,
                                 clocks->steps() * h_step,
                                 nullptr};
  double **x = atom->x;
  double **jump = scheme->jump();
  const int *mask = atom->mask;
  const int nlocal = atom->nlocal;
  const PEJump::FreeFlight vhalf = free_flight();
  double *tpos = clocks->times();
  double local[StabilityGuard::NMEASURES] = {0.0, 0.0, 0.0, 0.0, 0.0};
  clocks->moving_at(t);
  guard->forget_reach();    // the next coarse step moves other atoms
  for (int i = 0; i < nlocal; i++) {
    if (!(mask[i] & groupbit)) continue;
    const double v[3] = {vhalf(i, 0), vhalf(i, 1), vhalf(i, 2)};
    const bool lags = (tpos[i] != AsyncClocks::MOVING);
    StabilityGuard::measure_one(x[i], xhold ? xhold[i] : nullptr, v, jump[i], at,
                                at.select && at.select[i], lags ? elapsed - tpos[i] : 0.0, local);
    const double dt = lags ? clocks->now() - tpos[i] : t;
    for (int k = 0; k < 3; k++) x[i][k] += dt * v[k];
    tpos[i] = AsyncClocks::MOVING;
  }
  if (!within) guard->all_measured(local[0], MAX(span, at.hsel), clocks->steps());
  finish_check(local);
  if (first->moved_too_far(groupbit, true, within)) next_reneighbor = update->ntimestep;
}

/* ----------------------------------------------------------------------
   an energy minimization moves the atoms and keeps the velocities: the
   next run restarts the scheme
------------------------------------------------------------------------- */

void FixPEJumpAsync::min_setup(int /*vflag*/)
{
  scheme->atoms_minimized();
}

/* ---------------------------------------------------------------------- */

void FixPEJumpAsync::setup(int /*vflag*/)
{
  // (mid coarse step the positions belong to different times)
  scheme->agree_on_started(group_atoms(), style, opts.compensate < 0,
                           nodes->tallied(clocks->at_coarse_node()));
  // the buffer is assigned when the scheme starts, or again if the restart
  // file was written with other buffer layers
  state->ensure(atom->nlocal);
  if (assign->assign_buffer(scheme->started, *split)) split->invalidate();
  // a run with "pre no" keeps the lists of the previous run: split them if
  // this fix has not seen them yet
  if (!split->up_to_date()) post_neighbor();
  first->require_fine_clock(groupbit, assign->clock_bit(), opts.buffer_layers > 0);
  refuse_pair_misfit();
  // start nodes of slow atoms inside a coarse step cannot be taken again:
  // new atoms take theirs at their first evaluation
  scheme->fresh = 0;
  changes_seen = 0;
  opened_ahead = 0;
  assign->warn_if_made_static();
  check_clocks();

  grow_work();
  guard->start_run(!watch(OtherFixes::BETWEEN_STEPS | OtherFixes::INSIDE_STEP) &&
                   !domain->box_change);
  evals.step = 0.0;
  if (!scheme->started)
    start_scheme(nullptr, true);
  else
    continue_scheme();
  // the next run compares the energy of the last coarse node, if the run
  // ends at one (the clocks as the scheme's start or restart left them)
  if ((update->laststep - update->ntimestep + clocks->done()) % clocks->steps() == 0)
    nodes->ask_energy_at(update->laststep);
  if (!rule->only_end_nodes()) others->refuse_interactions(rule->name().c_str());
  slow_magnitudes();
  comm->forward_comm();    // the scheme's start may have caught up interior slow atoms
  classes->label(*split, *assign, groupbit);
  warn_output_between_nodes();
}

/* ----------------------------------------------------------------------
   pair styles whose forces the split cannot put on the clocks, as the
   probes of the split tell them at setup
------------------------------------------------------------------------- */

void FixPEJumpAsync::refuse_pair_misfit() const
{
  const auto fit = split->pair_fit();
  if (fit == InteractionSplit::OFF_LISTS)
    error->all(FLERR,
               "Fix pe_jump/async cannot split pair style {}: it computes forces that are not in "
               "its neighbor lists (e.g. from partner lists of its own). Use fix pe_jump",
               force->pair_style);
  if (fit == InteractionSplit::OFF_PAIRS)
    error->all(FLERR,
               "Fix pe_jump/async cannot split pair style {}: the force of a pair acts on other "
               "atoms than the two of the pair (e.g. on the hydrogen of a hydrogen bond, or on "
               "the atoms of TIP4P molecules), which the split cannot put on their clocks. Use "
               "fix pe_jump",
               force->pair_style);
  if (fit == InteractionSplit::NOT_ADDITIVE)
    error->all(FLERR,
               "Fix pe_jump/async cannot split pair style {}: the force of two pairs of an atom is "
               "not the sum of the forces of each (a many-body style, e.g. local/density, whose "
               "pair forces depend on the atoms' local densities). Use fix pe_jump",
               force->pair_style);
  if (fit == InteractionSplit::ON_TIME)
    error->all(FLERR,
               "Fix pe_jump/async cannot take pair style {}: its forces depend on the time or the "
               "step (e.g. pair_style hybrid/scaled with a variable of time), which the fine and "
               "coarse nodes would see at the end of the step (first order). Use fix pe_jump",
               force->pair_style);
}

/* ----------------------------------------------------------------------
   thermo output, dumps or fixes that sample (fix ave/time, ...) on steps
   that are not coarse nodes see the slow atoms' velocities of the coarse
   step's start (first order in the coarse step): a warning, once per run
------------------------------------------------------------------------- */

void FixPEJumpAsync::warn_output_between_nodes() const
{
  const bigint k = clocks->steps();
  const bigint slow = slow_total();    // (all on the fine clock: no warning)
  // (a rerun integrates nothing: its snapshots are states of their own)
  if ((comm->me != 0) || (k <= 1) || (slow == 0) || scheme->reading_snapshots()) return;
  const bigint now = update->ntimestep, last = update->laststep;
  const bigint node = now - clocks->done();    // the last coarse node
  const auto between = [&](bigint step) {
    return (step - node) % k != 0;
  };
  // a step of this run that is a multiple of every and no coarse node
  // (the pattern repeats after k multiples)
  const auto off_nodes = [&](int every, bool variable) {
    if (variable) return true;
    if (every <= 0) return false;
    bigint step = ((now + every - 1) / every) * every;
    for (bigint m = 0; (m < k) && (step <= last); ++m, step += every)
      if (between(step)) return true;
    return false;
  };
  std::string what;
  if (off_nodes(output->thermo_every, output->var_thermo != nullptr) || between(now) ||
      between(last))
    what = "thermo output";
  for (int i = 0; i < output->ndump; i++)
    if (off_nodes(output->every_dump[i], output->every_dump[i] == 0)) {
      what += what.empty() ? "dump " : ", dump ";
      what += output->dump[i]->id;
    }
  // fixes that sample values at the end of steps every Nevery steps (fix
  // ave/time, ave/correlate, ave/atom, vector, print, store/state, halt, ...)
  const std::string samplers = others->named([&](Fix *fix) {
    return OtherFixes::style_is(fix, {"^ave/", "^vector", "^print", "^store/state", "^halt"}) &&
        off_nodes(fix->nevery, false);
  });
  if (!samplers.empty()) what += (what.empty() ? "" : ", ") + samplers;
  if (!what.empty())
    error->warning(FLERR,
                   "Fix {}: {} on steps that are not coarse nodes (every {} steps from step {}): "
                   "there the slow atoms' velocities (ke, temp, press, dumped velocities, computes "
                   "that use them) are those of the coarse step's start",
                   style, what, k, node);
}

/* ----------------------------------------------------------------------
   the state carried over (earlier run, restart): velocities changed since
   restart the scheme; a reversal of all of them at a coarse node goes on
   backwards in time (inside a coarse step the slow atoms have no node
   velocity to reverse)
------------------------------------------------------------------------- */

void FixPEJumpAsync::continue_scheme()
{
  const int change = scheme->velocity_change(group_atoms(), clocks->at_coarse_node());
  if ((change == 2) && !clocks->at_coarse_node()) refuse_slow_velocity_changes();
  if (change == 2)
    start_scheme("velocities were changed since the last run: restarting the two-step scheme "
                 "from the current positions and velocities",
                 true);
  if ((change == 1) && (comm->me == 0))
    utils::logmesg(lmp, "Fix {}: all velocities were reversed: continuing backwards in time\n",
                   style);
}

/* ---------------------------------------------------------------------- */

bigint FixPEJumpAsync::slow_total() const
{
  // atoms of the group off the fine clock (from the masks: also before
  // the first list build, e.g. after read_restart)
  const int *mask = atom->mask;
  const int clock = assign->clock_bit();
  bigint local = 0, all = 0;
  for (int i = 0; i < atom->nlocal; i++)
    if ((mask[i] & groupbit) && !(mask[i] & clock)) ++local;
  MPI_Allreduce(&local, &all, 1, MPI_LMP_BIGINT, MPI_SUM, world);
  return all;
}

/* ----------------------------------------------------------------------
   inside a coarse step atom->v of a slow atom is its velocity at the
   coarse step's start, without the impulses of its fine interactions
   since (in facc): a command that set velocities acted on those
------------------------------------------------------------------------- */

void FixPEJumpAsync::refuse_slow_velocity_changes()
{
  const int local = scheme->any_changed({0, &assign->slow_atoms}) ? 1 : 0;
  int any = 0;
  MPI_Allreduce(&local, &any, 1, MPI_INT, MPI_MAX, world);
  if (any)
    error->all(FLERR,
               "Fix {}: velocities of slow atoms were changed since the last run, which ended "
               "inside a coarse step ({} of {} fine steps done): there a slow atom's velocity is "
               "that of the coarse step's start, without the impulses since. End the run at a "
               "coarse node (a multiple of K steps) before changing velocities, or unfix the "
               "fix first",
               style, clocks->done(), clocks->steps());
}

/* ----------------------------------------------------------------------
   write_data inside a coarse step would write the slow atoms' velocities
   of the coarse step's start, without the impulses since, and positions
   that may lag (none of this with every atom on the fine clock)
------------------------------------------------------------------------- */

void FixPEJumpAsync::refuse_data_file() const
{
  if (scheme->started && !clocks->at_coarse_node() && (slow_total() > 0))
    error->all(FLERR,
               "Fix {}: write_data inside a coarse step ({} of {} fine steps done) would write "
               "the slow atoms' velocities of the coarse step's start and positions of other "
               "times: end the run at a coarse node (a multiple of K steps), or use "
               "write_restart, which keeps the state of the fix",
               style, clocks->done(), clocks->steps());
}

/* ---------------------------------------------------------------------- */

void FixPEJumpAsync::setup_pre_reverse(int eflag, int vflag)
{
  pre_reverse(eflag, vflag);
}

/* ----------------------------------------------------------------------
   the fine steps begin; on the last fine step of a coarse step every atom
   moves to the primary node, else the atoms that move on fine steps
------------------------------------------------------------------------- */

void FixPEJumpAsync::initial_integrate(int /*vflag*/)
{
  const double h_step = update->dt;    // the fine step
  if (scheme->awaits_setup() &&
      scheme->check_run_without_setup(style, group_atoms(), assign->changed()))
    next_reneighbor = update->ntimestep;
  if (reinit_pending) start_scheme(nullptr, false);
  reinit_pending = 0;
  if (clocks->at_coarse_node() && scheme->started) change_clocks();
  if (!opened_ahead) {
    node_impulses();
    open_steps();
  }
  const double t = rule->node[rule->primary()] * h_step;
  if (clocks->last_fine_step()) {
    all_to_primary_node(t);
  } else {
    check_lists();
    advance(t);
  }
  opened_ahead = 0;
  if (guard->rebuild_forced()) ahead_for_build();
}

/* ----------------------------------------------------------------------
   lists that LAMMPS rebuilds in this step whatever the atoms do
   (neigh_modify check no, which misses the pairs beyond the skin) are
   built where a run continued after this step builds them: every atom at
   the step end. The slow atoms that sit out the fine steps catch up there
   (and stay); those that move (on the last fine step of a coarse step:
   all) go on from their primary node, and back_from_build() brings them
   back after the build, before the clocks hold the atoms that sit out
   the next fine steps (at the primary node's time)
------------------------------------------------------------------------- */

void FixPEJumpAsync::ahead_for_build()
{
  const double h_step = update->dt;    // the fine step
  const double rest = (1.0 - rule->node[rule->primary()]) * h_step;
  clocks->moving_at(h_step);
  clocks->catch_up_all(free_flight(), assign->moving());
  if (rest == 0.0) return;
  move_moving(rest);
  build_ahead = rest;
}

/* ---------------------------------------------------------------------- */

void FixPEJumpAsync::back_from_build()
{
  move_moving(-build_ahead);
  clocks->moving_at(rule->node[rule->primary()] * update->dt);
  build_ahead = 0.0;
  comm->forward_comm();
}

/* ----------------------------------------------------------------------
   free flight over dt of the atoms of the group that move with the fine
   steps (their clock time is MOVING)
------------------------------------------------------------------------- */

void FixPEJumpAsync::move_moving(double dt)
{
  const PEJump::FreeFlight vhalf = free_flight();
  double **x = atom->x;
  const double *tpos = clocks->times();
  group_atoms().each(atom->mask, atom->nlocal, [&](int i) {
    if (tpos[i] == AsyncClocks::MOVING)
      for (int k = 0; k < 3; k++) x[i][k] += dt * vhalf(i, k);
  });
}

/* ----------------------------------------------------------------------
   a dynamic fast group or fast auto: atoms change clock at coarse nodes,
   where every atom is at its node q^n with its node velocity v^n, which it
   keeps. The interactions are split again and the atoms sorted by clock
   again; the atoms that changed restart their jumps with the kick of the
   new step (restart_jumps()), from the forces at q^n
------------------------------------------------------------------------- */

void FixPEJumpAsync::change_clocks()
{
  std::vector<int> to_fine, chosen;
  if (opts.fast_auto > 0.0) choose_fast(chosen);
  const std::vector<int> *picked = chosen.empty() ? nullptr : &chosen;
  // (initial_integrate() of the step after the node)
  const bool due = assign->due(picked, update->ntimestep - 1, clocks->steps());
  // the midpoint rule takes the forces at the node from FINE subsets, the
  // first one of the old clocks (those who leave the fine clock), if two of
  // them cost less than a complete evaluation
  const bool by_subsets = due && !rule->has_end_nodes() && split->up_to_date() &&
      (split->fraction(InteractionSplit::FINE) < 0.5);
  if (by_subsets) {
    grow_work();
    evals.total += fine_forces_at_node(work->get(COARSE), nullptr);
  }
  // the buffer layers are the partners within the cutoff at the node: the
  // ghost atoms must be there too (without energy output at the node they
  // are still where the last primary node left them)
  if (due && (opts.buffer_layers > 0) && !by_subsets) comm->forward_comm();
  const bool changed = due && assign->follow(*split, to_fine, picked);
  if (due || !split->up_to_date()) {
    split->build();
    assign->find_slow(*split);
    if (assign->find_moving(*split, *clocks, free_flight())) comm->forward_comm();
    first->find_partners(assign->participants(), assign->moving(), groupbit);
  }
  if (!changed) return;
  // the forces at the node: with a Lobatto rule the start nodes of both
  // subsets are taken anew, and an atom's force is their sum (an
  // interaction of a fine-clock atom is a fine one), else the FINE subset
  // of the new clocks for those who join the fine clock
  if (rule->has_end_nodes()) {
    store_start_node();
    grow_work();
    double **total = work->get(SUM);
    double **fstart = scheme->fstart();
    double **fstart_coarse = state->vec(FSTART_COARSE);
    for (int i = 0; i < atom->nlocal; i++)
      for (int k = 0; k < 3; k++) total[i][k] = fstart[i][k] + fstart_coarse[i][k];
    restart_jumps(to_fine, total);
    evals.total += 1.0;
  } else if (by_subsets) {
    evals.total += fine_forces_at_node(work->get(COARSE), &to_fine);
    restart_jumps(to_fine, work->get(COARSE));
  } else {
    NodeSampler::Keep keep(*nodes);
    sampler->compute(ForceSampler::ALL, 0, 0);
    restart_jumps(to_fine, atom->f);
    evals.total += 1.0;
  }
  guard->forget_stats();
  slow_magnitudes();
  classes->label(*split, *assign, groupbit);
}

/* ----------------------------------------------------------------------
   midpoint rule at a clock change: the forces at the node q^n of the atoms
   that change clock (rows of fnode; the work array of the coarse sum is
   free between coarse steps) without a complete evaluation. Every
   interaction of an atom on the fine clock is in the FINE subset, so its
   force from that subset is complete, summed in the same order. With the
   old clocks: rows of every atom on the fine clock (among them those who
   leave it); with the new ones (to_fine): rows of those who joined it.
   Returns the cost in evaluations
------------------------------------------------------------------------- */

double FixPEJumpAsync::fine_forces_at_node(double **fnode, const std::vector<int> *to_fine)
{
  const int nlocal = atom->nlocal;
  const auto wanted = [&](int i) {
    return to_fine ? ((*to_fine)[i] > 0) : (split->fine(i) != 0);
  };
  int local = 0, any = 0;
  for (int i = 0; i < nlocal && !local; i++) local = wanted(i) ? 1 : 0;
  MPI_Allreduce(&local, &any, 1, MPI_INT, MPI_MAX, world);
  if (!any) return 0.0;

  NodeSampler::Keep keep(*nodes);
  split->activate(InteractionSplit::FINE);
  sampler->compute(ForceSampler::ALL, 0, 0);
  split->restore();
  double **f = atom->f;
  for (int i = 0; i < nlocal; i++)
    if (wanted(i))
      for (int k = 0; k < 3; k++) fnode[i][k] = f[i][k];
  return split->fraction(InteractionSplit::FINE);
}

/* ----------------------------------------------------------------------
   fast auto TOL: at a coarse node, the atoms of the fix group that would
   move by more than TOL times the neighbor skin over a coarse step on the
   coarse clock, h_S |v^n + (h_S/h) [v]^n/2| with h their present step (the
   free flight of their next step with the jump fitted to the coarse
   step), go on the fine clock; those on it stay while they would move by
   more than half that (no flapping between the clocks)
------------------------------------------------------------------------- */

void FixPEJumpAsync::choose_fast(std::vector<int> &chosen) const
{
  const int nlocal = atom->nlocal;
  const int *mask = atom->mask;
  const int *slow = assign->slow();
  double **v = atom->v;
  double **jump = scheme->jump();
  const double coarse = clocks->steps() * update->dt;
  const double limit = opts.fast_auto * neighbor->skin;
  chosen.assign(nlocal, 0);
  for (int i = 0; i < nlocal; i++) {
    if (!(mask[i] & groupbit)) continue;
    const double ratio = slow[i] ? 1.0 : static_cast<double>(clocks->steps());
    double d2 = 0.0;
    for (int k = 0; k < 3; k++) {
      const double u = v[i][k] + 0.5 * ratio * jump[i][k];
      d2 += u * u;
    }
    const double d = coarse * sqrt(d2);
    chosen[i] = (d > limit) || (!slow[i] && (d > 0.5 * limit));
  }
}

/* ----------------------------------------------------------------------
   the atoms that changed clock (to_fine[i] = 1: to the fine clock, -1: to
   the coarse clock) start their new clock with the initial kick of the
   scheme, [v]^n = h_new F(q^n)/m, with f the forces at the node (the
   smooth jump of the new step; whatever parasitic jump the old clock
   carried is dropped). Node velocities are untouched, and with them the
   momentum. The jumps are not shifted to keep sum m [v]: a common shift
   of the changed jumps is a parasitic jump of its own (for a single atom
   it undoes the restart), and atoms that change clock at every node
   pumped it up to a first-order error.
------------------------------------------------------------------------- */

void FixPEJumpAsync::restart_jumps(const std::vector<int> &to_fine, double **f)
{
  AtomList changed;
  for (int i = 0; i < atom->nlocal; i++)
    if (to_fine[i] && (atom->mask[i] & groupbit)) changed.push_back(i);
  const PEJump::AtomSet atoms = group_atoms(&changed);
  double before[2], after[2];
  scheme->energies_now(atoms, before);
  const double fine = update->dt, coarse = clocks->steps() * update->dt;
  scheme->start(atoms, f, 1.0, [&](int i) {
    return (to_fine[i] > 0) ? fine : coarse;
  });
  scheme->energies_now(atoms, after);
  // the pseudo-energy pe + (1/2) sum m v^{n-1/2}.v^{n+1/2} = pe + kinetic -
  // jump energy, with positions and node velocities kept
  assign->add_change_energy(
      before[1] - after[1],
      [&]() {
        double e[2];
        scheme->energies_now(group_atoms(), e);
        return e[0] + e[1];
      },
      style);
}

/* ----------------------------------------------------------------------
   (re)start the two-step scheme from the current positions, velocities and
   forces (see fix pe_jump), with a new coarse step; a slow atom's initial
   kick is over the coarse step
------------------------------------------------------------------------- */

void FixPEJumpAsync::start_scheme(const char *why, bool with_start)
{
  catch_up_all();
  if (with_start) {
    if (!clocks->at_coarse_node() && !scheme->reading_snapshots())
      hand_over_impulses("the two-step scheme restarts");
    clocks->begin_coarse();
    double **facc = state->vec(FACC);
    for (int i = 0; i < atom->nlocal; i++)
      for (int k = 0; k < 3; k++) facc[i][k] = 0.0;
  }
  if (why && (comm->me == 0)) utils::logmesg(lmp, "Fix {}: {}\n", style, why);

  grow_work();
  if (with_start && rule->has_end_nodes()) store_start_node();
  const double kick = (opts.init_style == PEJump::Options::KICK) ? 1.0 : 0.0;
  const double fine = update->dt, coarse = clocks->steps() * update->dt;
  scheme->start(group_atoms(), atom->f, kick, [&](int i) {
    return split->coarse(i) ? coarse : fine;
  });
  // fixes defined after this one act on the forces after its setup(): redo
  // the initial kick with the complete forces at the first step
  reinit_pending =
      with_start && (opts.init_style == PEJump::Options::KICK) && sampler->has_projections();
  scheme->started = 1;
  guard->forget_stats();
}

/* ---------------------------------------------------------------------- */

std::string FixPEJumpAsync::instability_advice() const
{
  return fmt::format("The fine step {} (fast and mixed atoms), the coarse step {} (slow atoms), or "
                     "their coupling at the interface, which has resonances (see the stability "
                     "section of the fix pe_jump/async documentation), is unstable: reduce the "
                     "time step or change K{}",
                     update->dt, clocks->steps() * update->dt,
                     opts.buffer_layers ? ""
                                        : ", or add the keyword buffer 1 (the slow partners of "
                                          "the interface then take the fine step)");
}

/* ----------------------------------------------------------------------
   inside a coarse step a slow atom keeps its node velocity v^n of the
   coarse step's start, and the impulse of the fine interactions on it
   since then waits in FACC for the coarse node, while the fast atoms got
   theirs at every fine step. When the coarse step is broken off (the
   scheme restarts, the fix is removed) the slow atoms get that impulse,
   so that the total momentum stays what the scheme left; the impulse of
   the interactions among slow atoms over the broken coarse step, whose
   sum is zero, is not given (an O(h) change of the slow velocities, as
   from a new start of the scheme, which makes the run first order: a
   warning names the event)
------------------------------------------------------------------------- */

void FixPEJumpAsync::hand_over_impulses(const std::string &event)
{
  if (comm->me == 0)
    error->warning(FLERR,
                   "Fix {}: {} inside a coarse step ({} of {} fine steps done): the slow atoms "
                   "miss the impulse of the interactions among them over those steps, an error "
                   "of first order in the time step. Change the time step, masses, positions, "
                   "velocities, atoms or fixes at coarse nodes (after a multiple of K steps)",
                   style, event, clocks->done(), clocks->steps());
  double **v = atom->v;
  double **facc = state->vec(FACC);
  const double ftm2v = force->ftm2v;
  const int *mask = atom->mask;
  // FACC is zero but for slow atoms (and moves with the atoms, which the
  // clock flags may not have followed since the last run)
  for (int i = 0; i < atom->nlocal; i++) {
    if (!(mask[i] & groupbit)) continue;
    const double dv = ftm2v * scheme->inverse_mass_of(i);
    for (int k = 0; k < 3; k++) v[i][k] += dv * facc[i][k];
  }
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

double FixPEJumpAsync::node_cost() const
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
  first->clear_stale_forces();
  split->activate(InteractionSplit::FINE);
}

/* ----------------------------------------------------------------------
   with neigh_modify include, Verlet::setup() cleared the forces of the
   include group only
------------------------------------------------------------------------- */

void FixPEJumpAsync::setup_pre_force(int /*vflag*/)
{
  first->clear_before_setup();
}

/* ---------------------------------------------------------------------- */

void FixPEJumpAsync::pre_reverse(int eflag, int vflag)
{
  split->restore();
  nodes->note_step_flags(eflag, vflag);
}

/* ----------------------------------------------------------------------
   the nodes of a fine step inside a coarse step (the atoms on the fine
   clock and the slow atoms in a fine interaction move to them)
------------------------------------------------------------------------- */

void FixPEJumpAsync::check_lists()
{
  const double h_step = update->dt;    // the fine step
  const int first_node = rule->has_end_nodes() ? 1 : 0;
  const double c_lo = rule->node[first_node];
  const bool tally = nodes->step_end_evaluated();
  const double c_hi = tally ? 1.0 : rule->node.back();
  // atoms opened ahead are at the primary node already: the nodes from there
  const double from = opened_ahead ? rule->node[rule->primary()] : 0.0;
  double **xhold = neighbor->dist_check ? neighbor->get_xhold() : nullptr;
  double local[StabilityGuard::NMEASURES] = {0.0, 0.0, 0.0, 0.0, 0.0};
  guard->step(h_step);
  if (guard->has_stats()) {
    // the magnitudes were taken per clock by final_integrate(); the fine
    // nodes' excursions matter only for the atoms that move to them, and
    // not at all if the Verlet loop checks the only node or the step ends.
    // On steps that neigh_modify every or delay exempt from LAMMPS' check,
    // those atoms are the only ones that moved since the last check: the
    // fix checks them, and the lists stay those of every 1 delay 0 (not
    // with neigh_modify once yes, which asks for no rebuild)
    const bool unchecked = !neighbor->build_once && !StabilityGuard::lists_checked_now(neighbor);
    const double coarse_step = clocks->steps() * h_step;
    const double hf2 = h_step * h_step, hs2 = coarse_step * coarse_step;
    local[1] = MAX(hf2 * guard->speed2(), hs2 * guard->slow_speed2());
    local[2] = MAX(hf2 * guard->jump2(), hs2 * guard->slow_jump2());
    local[3] = MAX(guard->jump2(), guard->slow_jump2());
    local[4] = MAX(guard->speed2(), guard->slow_speed2());
    // (whether LAMMPS' check of the step ends covers the nodes is a matter
    // of where they lie in the step, wherever the atoms are now)
    const double lo = (c_lo - from) * h_step, hi = (c_hi - from) * h_step;
    if (xhold && (tally || unchecked || (rule->size() > 1)) &&
        !guard->ends_checked(*rule, c_lo * h_step, c_hi * h_step, h_step))
      local[0] =
          guard->excursion_since(group_atoms(&assign->moving_atoms), free_flight(), xhold, lo, hi);
    else
      guard->forget_reach();
  } else {
    const double cp = rule->node[rule->primary()] * h_step;
    const StabilityGuard::Nodes at{
        h_step,         c_lo * h_step, c_hi * h_step, cp,
        assign->slow(), 0.0,           0.0,           clocks->steps() * h_step,
        nullptr};
    guard->measure(group_atoms(), free_flight(), scheme->jump(), xhold, at, local);
  }
  finish_check(local);
}

/* ----------------------------------------------------------------------
   act on the stability guard's verdict (the ranks agree)
------------------------------------------------------------------------- */

void FixPEJumpAsync::finish_check(const double *local)
{
  double none = 0.0;
  if (guard->conclude(
          style, local, none,
          [&]() {
            return scheme->energies(group_atoms());
          },
          [&]() {
            return instability_advice();
          }))
    next_reneighbor = update->ntimestep;
}

/* ----------------------------------------------------------------------
   fsum = sum_k w_k F_fine(q_k) for the atoms that move on fine steps; the
   primary node p was evaluated by the Verlet loop, a Lobatto start node is
   the previous fine step's end node
------------------------------------------------------------------------- */

void FixPEJumpAsync::fine_quadrature_sum()
{
  const int p = rule->primary();
  const double wp = rule->weight[p];
  const int reuse_start = rule->has_end_nodes();
  double **f = atom->f;
  double **fstart = scheme->fstart();
  double **fsum = work->get(SUM);
  const AtomList &moving = assign->moving_atoms;

  // the end node's forces are the next step's start node (fstart); on the
  // last fine step every atom's are kept for reach_coarse_node(), which the
  // coarse evaluations overwrite in f
  if (reuse_start && atom->nlocal && clocks->last_fine_step())
    memcpy(&work->get(SAMPLE)[0][0], &f[0][0], 3 * sizeof(double) * atom->nlocal);
  // (the end node's forces are the next start node's once read)
  for (const int i : moving) {
    if (reuse_start && std::isnan(fstart[i][0]))
      for (int k = 0; k < 3; k++) fstart[i][k] = f[i][k];
    for (int k = 0; k < 3; k++) {
      fsum[i][k] = wp * f[i][k];
      if (reuse_start) {
        fsum[i][k] += rule->weight[0] * fstart[i][k];
        fstart[i][k] = f[i][k];
      }
    }
  }
  const int first = reuse_start ? 1 : 0;
  if (rule->size() - first <= 1) return;
  const int evaluated =
      nodes->sum_nodes(*rule, first, p, update->dt, -rule->node[p] * update->dt, free_flight(),
                       group_atoms(&moving), opts.sample_mask, fsum, nullptr, step_forces_read());
  evals.step += evaluated * node_cost();
}

/* ----------------------------------------------------------------------
   true if anything may read atom->f between this fine step's end and the
   force clearing of the next step: the coarse evaluation of the last fine
   step, output and fixes at the end of the step, fixes that act between
   the steps, a run that a timeout may end here (the next run may start
   with pre no). Elsewhere the node evaluations inside the step need not
   put the forces of the step end back. (There is no other time
   integrator to read them: refuse_other_fixes())
------------------------------------------------------------------------- */

bool FixPEJumpAsync::step_forces_read() const
{
  return clocks->last_fine_step() || others->step_observed() ||
      watch(OtherFixes::BETWEEN_STEPS | OtherFixes::INSIDE_STEP) || timer->has_timeout();
}

/* ----------------------------------------------------------------------
   fcoarse = sum_k w_k F_slow(q_S^n + c_k H v_S) for the slow atoms, from
   the positions of the primary fine node, inside keep (which keeps those
   positions); the Lobatto start node is the end node of the previous
   coarse step
------------------------------------------------------------------------- */

void FixPEJumpAsync::coarse_quadrature_sum(NodeSampler::Keep &keep, const PEJump::AtomSet &slow)
{
  const int reuse_start = rule->has_end_nodes();
  double **fstart_coarse = reuse_start ? state->vec(FSTART_COARSE) : nullptr;
  double **fcoarse = work->get(COARSE);
  // (without a start node the first node's terms set fcoarse)
  if (reuse_start)
    for (const int i : assign->slow_atoms)
      for (int k = 0; k < 3; k++) fcoarse[i][k] = rule->weight[0] * fstart_coarse[i][k];
  const double coarse_step = clocks->start() + update->dt;
  const double at = clocks->start() + rule->node[rule->primary()] * update->dt;
  split->activate(InteractionSplit::COARSE);
  const int evaluated =
      nodes->sum_nodes_in(keep, *rule, reuse_start ? 1 : 0, -1, coarse_step, -at, free_flight(),
                          slow, opts.sample_mask, fcoarse, fstart_coarse, reuse_start);
  evals.step += evaluated * node_cost();
  split->restore();
}

/* ----------------------------------------------------------------------
   the last fine step of a coarse step: the coarse quadrature sum, then
   every atom reaches the coarse node. The slow atoms move on from their
   positions at the primary fine node as kept while the coarse nodes moved
   them (they are not copied back first)
------------------------------------------------------------------------- */

void FixPEJumpAsync::coarse_node(double **favg, double mag[2][2])
{
  // the fine evaluation left forces on the atoms that move on fine steps
  // only (no fix adds forces, refuse_other_fixes()), unless atoms outside
  // the group take part
  const PEJump::AtomSet slow = group_atoms(&assign->slow_atoms);
  NodeSampler::Keep keep(*nodes, NodeSampler::positions_for(slow), slow.list, true,
                         (igroup == 0) ? &assign->moving_atoms : nullptr);
  coarse_quadrature_sum(keep, slow);
  keep.forces_back();
  reach_coarse_node(favg, mag, keep.positions());
  keep.positions_taken();
}

/* ----------------------------------------------------------------------
   forces of the fine interactions at the primary fine node are known:
   sample the other fine nodes, on the last fine step the coarse nodes, then
   jump (fast and mixed atoms every fine step, slow atoms at coarse nodes)
   and move on to the end of the fine step
------------------------------------------------------------------------- */

void FixPEJumpAsync::final_integrate()
{
  const double h_step = update->dt;    // the fine step
  const bool coarse_end = clocks->last_fine_step();
  // a slow atom keeps its velocity over the coarse step: a change by a fix
  // inside any of its fine steps is still there at the last one
  if (watch(OtherFixes::INSIDE_STEP))
    note_velocity_changes(coarse_end ? nullptr : &assign->fast_atoms);
  grow_work();

  // with a single node, evaluated by the Verlet loop with nothing else to
  // separate, the forces there are the fine quadrature average itself
  evals.step = split->fraction(InteractionSplit::FINE);
  const bool direct = (rule->size() == 1);
  if (!direct) {
    // with neigh_modify include the node evaluations clear and keep the
    // forces of the atoms they act on only
    split->activate(InteractionSplit::FINE);
    sampler->only_touch(first->fine_atoms());
    fine_quadrature_sum();
    sampler->only_touch(nullptr);
    split->restore();
  }
  // per clock: largest |v|^2, |[v]|^2 (the slow atoms' change at coarse nodes)
  double mag[2][2] = {{0.0, 0.0}, {0.0, 0.0}};
  double **favg = direct ? atom->f : work->get(SUM);
  if (coarse_end)
    coarse_node(favg, mag);
  else
    continue_fine_step(favg, mag[0]);
  guard->set_stats(mag[0][0], mag[0][1]);

  // interior slow atoms catch up wherever their positions are looked at:
  // output, other fixes at the end of the step, the end of the run
  clocks->end_fine(h_step);
  if (!coarse_end && others->step_observed()) catch_up_all();

  split->activate(InteractionSplit::ALL);
  // no other time integrator (refuse_other_fixes()): no atoms to leave out
  const double at_end = nodes->at_step_end(others->step_observed(), 0);
  split->restore();
  evals.step += at_end;
  if (at_end > 0.0) first->forces_written();    // on every atom
  evals.total += evals.step;
  scheme->forget_energies();

  // the labels are output only: take them where something looks, when
  // at_step_end() has brought the ghosts to the node
  const bool ghosts_at_node = nodes->step_tallies() || others->step_observed();
  if (coarse_end && ghosts_at_node) classes->label(*split, *assign, groupbit);
  if (coarse_end) assign->evaluate_at_node(update->ntimestep, clocks->steps(), ghosts_at_node);
}

/* ----------------------------------------------------------------------
   the last fine step of a coarse step: every atom reaches the coarse node
   from its primary fine node (xslow: the slow atoms' positions there), the
   atoms on the fine clock jump with favg, the slow ones with the sums of
   their fine forces over the coarse step and the coarse quadrature sum
------------------------------------------------------------------------- */

void FixPEJumpAsync::reach_coarse_node(double **favg, double mag[2][2], double **xslow)
{
  const double h_step = update->dt;    // the fine step
  double **x = atom->x;
  double **v = atom->v;
  double **f = atom->f;
  double **jump = scheme->jump();
  double **facc = state->vec(FACC);
  double **fstart = scheme->fstart();
  double *tpos = clocks->times();
  double **fsample = work->get(SAMPLE);
  double **fcoarse = work->get(COARSE);
  const int *slow = assign->slow(), *moving = assign->moving();
  double *vsig = watch(OtherFixes::BETWEEN_STEPS | OtherFixes::INSIDE_STEP) ? scheme->vsig()
                                                                            : nullptr;
  const double *rmass = atom->rmass;
  const double *minv = scheme->inverse_masses();
  const int *type = atom->type;
  const double rest = (1.0 - rule->node[rule->primary()]) * h_step;
  const double coarse_step = clocks->start() + h_step;
  const double kick_fine = 2.0 * h_step * force->ftm2v;
  const double kick_coarse = 2.0 * coarse_step * force->ftm2v;
  const int *mask = atom->mask;
  const int nlocal = atom->nlocal;
  // (a plain loop and local maxima: the compiler keeps them in registers)
  double most_fine[2] = {mag[0][0], mag[0][1]}, most_slow[2] = {mag[1][0], mag[1][1]};
  for (int i = 0; i < nlocal; i++) {
    if (!(mask[i] & groupbit)) continue;
    const double dt = (tpos[i] == AsyncClocks::MOVING) ? rest : coarse_step - tpos[i];
    if (fstart)
      for (int k = 0; k < 3; k++) fstart[i][k] = fsample[i][k];
    // interior slow atoms have no fine interactions: only other fixes' forces
    const double *fa = moving[i] ? favg[i] : f[i];
    const double inv = rmass ? 1.0 / rmass[i] : minv[type[i]];
    if (!slow[i]) {
      for (int k = 0; k < 3; k++) x[i][k] += dt * v[i][k];
      PEJump::TwoStep::jump_one(kick_fine * inv, fa, v[i], jump[i], most_fine);
    } else {
      double fslow[3];
      for (int k = 0; k < 3; k++) {
        fslow[k] = (facc[i][k] + h_step * fa[k]) / coarse_step + fcoarse[i][k];
        facc[i][k] = 0.0;
        v[i][k] += 0.5 * jump[i][k];    // into its step
        x[i][k] = xslow[i][k] + dt * v[i][k];
      }
      PEJump::TwoStep::jump_one(kick_coarse * inv, fslow, v[i], jump[i], most_slow);
    }
    if (vsig) vsig[i] = PEJump::velocity_fingerprint(v[i]);
    tpos[i] = moving[i] ? AsyncClocks::MOVING : 0.0;    // at the next coarse step's start
  }
  for (int k = 0; k < 2; k++) {
    mag[0][k] = most_fine[k];
    mag[1][k] = most_slow[k];
  }
  guard->set_slow_stats(mag[1][0], mag[1][1]);
}

/* ----------------------------------------------------------------------
   true if the next fine step, inside the same coarse step, can begin as
   this one ends (continue_fine_step() opens it and moves the moving atoms
   on to its primary node): a single-node rule or a Lobatto rule (its
   primary node is the step end), nothing that looks at the atoms or may
   change their velocities in between, lists checked by distance, no
   timeout that may end the run before the next step
------------------------------------------------------------------------- */

bool FixPEJumpAsync::may_open_ahead() const
{
  return ((rule->size() == 1) || rule->has_end_nodes()) && !clocks->next_is_last() &&
      neighbor->dist_check && !reinit_pending && !watch(OtherFixes::BETWEEN_STEPS) &&
      !others->step_observed() && !timer->has_timeout();
}

/* ----------------------------------------------------------------------
   inside a coarse step: the atoms on the fine clock take a synchronous
   step; of the slow atoms those in a fine interaction move on and collect
   the fine forces
------------------------------------------------------------------------- */

void FixPEJumpAsync::continue_fine_step(double **favg, double *mag)
{
  const double h_step = update->dt;    // the fine step
  double **x = atom->x;
  double **facc = state->vec(FACC);
  const PEJump::FreeFlight vhalf = free_flight();
  const double rest = (1.0 - rule->node[rule->primary()]) * h_step;
  opened_ahead = may_open_ahead();
  // the next fine step begins in the same pass, unless something looks
  const double ahead = opened_ahead ? rule->node[rule->primary()] * update->dt : -1.0;
  const bool fingerprint =
      watch(opened_ahead ? OtherFixes::INSIDE_STEP : OtherFixes::BETWEEN_STEPS);
  scheme->jump_loop(group_atoms(&assign->fast_atoms), favg, {h_step, rest, ahead, fingerprint},
                    mag);
  // the interior slow atoms get no fine forces: the fix refuses fixes that
  // add forces (refuse_other_fixes(); fix enforce2d, the only other one
  // allowed, zeroes a zero component). A Lobatto rule's next start node
  // was kept by fine_quadrature_sum()
  for (const int i : assign->slow_moving)
    for (int k = 0; k < 3; k++) {
      x[i][k] += rest * vhalf(i, k);
      if (opened_ahead) x[i][k] += ahead * vhalf(i, k);
      facc[i][k] += h_step * favg[i][k];
    }
}

/* ----------------------------------------------------------------------
   communication for the clock assignment: the fine clock of the ghost
   atoms (forward), flags set on ghosts (reverse)
------------------------------------------------------------------------- */

int FixPEJumpAsync::pack_forward_comm(int n, int *list, double *buf, int /*pbc_flag*/,
                                      int * /*pbc*/)
{
  return assign->pack_forward(n, list, buf);
}

/* ---------------------------------------------------------------------- */

void FixPEJumpAsync::unpack_forward_comm(int n, int first, double *buf)
{
  assign->unpack_forward(n, first, buf);
}

/* ---------------------------------------------------------------------- */

int FixPEJumpAsync::pack_reverse_comm(int n, int first, double *buf)
{
  return assign->reversing() ? assign->pack_reverse(n, first, buf) : 0;
}

/* ---------------------------------------------------------------------- */

void FixPEJumpAsync::unpack_reverse_comm(int n, int *list, double *buf)
{
  if (assign->reversing()) assign->unpack_reverse(n, list, buf);
}

/* ---------------------------------------------------------------------- */

double FixPEJumpAsync::compute_vector(int n)
{
  switch (n) {
    case 0:
    case 1:
      return scheme->energies(group_atoms())[n];
    case 2:
      return update->dt;
    case 3:
      return evals.step;
    case 4:
      return evals.total;
    case 5:
      return clocks->at_coarse_node() ? 1.0 : 0.0;
    case 6:
    case 7:
    case 8:
      return classes->count(n - 6);
  }
  return 0.0;
}

/* ----------------------------------------------------------------------
   the per-atom output (the classes) is a field of the state table, which
   may move when it grows
------------------------------------------------------------------------- */

void FixPEJumpAsync::show_classes()
{
  vector_atom = classes->classes();
}

/* ----------------------------------------------------------------------
   per-atom state: the table owns it and grows with the owned atoms
------------------------------------------------------------------------- */

void FixPEJumpAsync::grow_arrays(int /*nmax*/)
{
  state->ensure(atom->nlocal);
  show_classes();
}

/* ---------------------------------------------------------------------- */

void FixPEJumpAsync::copy_arrays(int i, int j, int /*delflag*/)
{
  state->copy(i, j);
  show_classes();
}

/* ----------------------------------------------------------------------
   an atom created during the simulation starts with its velocity and no
   jump (see fix pe_jump)
------------------------------------------------------------------------- */

void FixPEJumpAsync::set_arrays(int i)
{
  state->reset(i);
  scheme->mark(i);
  scheme->fresh = 1;
  show_classes();
}

/* ---------------------------------------------------------------------- */

int FixPEJumpAsync::pack_exchange(int i, double *buf)
{
  return state->pack(i, buf);
}

/* ---------------------------------------------------------------------- */

int FixPEJumpAsync::unpack_exchange(int nlocal, double *buf)
{
  const int m = state->unpack(nlocal, buf);
  show_classes();
  return m;
}

/* ---------------------------------------------------------------------- */

int FixPEJumpAsync::pack_restart(int i, double *buf)
{
  // written during a run: the velocities are the fix's own
  if (update->whichflag) scheme->mark(i);
  return state->pack_restart(i, buf);
}

/* ---------------------------------------------------------------------- */

void FixPEJumpAsync::unpack_restart(int nlocal, int nth)
{
  // a misfit is told by TwoStep::agree_on_started()
  if (!state->unpack_restart(nlocal, nth)) scheme->started = -1;
  show_classes();
}

/* ---------------------------------------------------------------------- */

int FixPEJumpAsync::size_restart(int /*nlocal*/)
{
  return state->restart_size();
}

/* ---------------------------------------------------------------------- */

int FixPEJumpAsync::maxsize_restart()
{
  return state->restart_size();
}

/* ----------------------------------------------------------------------
   global state: whether the two-step scheme runs, with which rule, the
   evaluations so far, (two values unused), K and the position inside the
   coarse step, the buffer layers and the atoms on the fine clock, the
   census, the buffer's reach
------------------------------------------------------------------------- */

void FixPEJumpAsync::write_restart(FILE *fp)
{
  // (+ 2: the census follows, + 4: and the buffer's reach, + 8: the fast
  // group is dynamic)
  double list[NGLOBAL] = {
      ((scheme->started > 0) ? 1.0 : 0.0) + 2.0 + 4.0 + (assign->dynamic_group() ? 8.0 : 0.0),
      static_cast<double>(rule->family()), static_cast<double>(rule->points()), evals.total};
  assign->save(&list[9], &list[4], &list[23]);
  clocks->save(&list[6]);
  scheme->save_census(&list[12]);
  if (comm->me == 0) {
    int size = sizeof(list);
    fwrite(&size, sizeof(int), 1, fp);
    fwrite(list, sizeof(double), NGLOBAL, fp);
  }
}

/* ---------------------------------------------------------------------- */

void FixPEJumpAsync::restart(char *buf)
{
  auto *list = reinterpret_cast<double *>(buf);
  const bool same_rule = (static_cast<int>(list[1]) == rule->family()) &&
      (static_cast<int>(list[2]) == rule->points());
  const int head = static_cast<int>(list[0]);
  // inside a coarse step, as for another K below
  if (!same_rule && ((head & 1) != 0) && (static_cast<int>(list[7]) != 0))
    error->all(FLERR,
               "Fix pe_jump/async: the restart file was written inside a coarse step ({} of {} "
               "fine steps done) with another quadrature, which this one cannot continue: read "
               "it with the quadrature of the file, or write restart files at coarse nodes "
               "(after multiples of K steps)",
               static_cast<int>(list[7]), static_cast<int>(list[6]));
  scheme->started = ((head & 1) != 0) && same_rule;
  evals.total = list[3];
  if (head >= 2) scheme->load_census(&list[12]);
  if (!same_rule && (comm->me == 0))
    utils::logmesg(lmp,
                   "Fix {}: quadrature differs from the restart file: the two-step scheme "
                   "restarts from the current state\n",
                   style);
  if (!clocks->restore(&list[6])) {
    // inside a coarse step the slow atoms' impulses of the fine steps done
    // belong to the old coarse step (see hand_over_impulses())
    if (static_cast<int>(list[7]) != 0)
      error->all(FLERR,
                 "Fix pe_jump/async: the restart file was written inside a coarse step ({} of "
                 "{} fine steps done), which K = {} cannot continue: read it with K = {}, or "
                 "write restart files at coarse nodes (after multiples of K steps)",
                 static_cast<int>(list[7]), static_cast<int>(list[6]), clocks->steps(),
                 static_cast<int>(list[6]));
    if (scheme->started && (comm->me == 0))
      utils::logmesg(lmp,
                     "Fix {}: K differs from the restart file: the two-step scheme restarts "
                     "from the current state\n",
                     style);
    scheme->started = 0;
    return;
  }
  assign->restore(&list[9], &list[4], (head >= 6) ? &list[23] : nullptr);
  if (head & 8) assign->restored_from_dynamic();
}

/* ----------------------------------------------------------------------
   if the atoms on the fine clock changed since the last run (the fast
   group redefined, a restart with another fast group or buffer), the
   two-step state of the atoms that changed clock no longer fits. At a
   coarse node the scheme restarts; inside a coarse step the slow atoms
   have no node state, so the change is refused.
------------------------------------------------------------------------- */

void FixPEJumpAsync::check_clocks()
{
  if (!assign->changed() || !scheme->started) return;
  if (!clocks->at_coarse_node())
    error->all(FLERR,
               "Fix pe_jump/async: the atoms on the fine clock changed inside a coarse step "
               "({} of {} fine steps done): change the fast group, or the buffer, only at a "
               "coarse node (after a multiple of K steps); after read_restart, define a dynamic "
               "fast group again before the fix",
               clocks->done(), clocks->steps());
  if (comm->me == 0)
    utils::logmesg(lmp,
                   "Fix {}: the atoms on the fine clock changed since the last run: restarting "
                   "the two-step scheme at this coarse node\n",
                   style);
  scheme->started = 0;
}

/* ---------------------------------------------------------------------- */

double FixPEJumpAsync::memory_usage()
{
  return state->memory_usage() + nodes->memory_usage() + work->memory_usage();
}

/* ----------------------------------------------------------------------
   the work arrays of the owned atoms that the rule needs
------------------------------------------------------------------------- */

void FixPEJumpAsync::grow_work()
{
  const int need = (1 << COARSE) | ((rule->size() > 1) ? 1 << SUM : 0) |
      (rule->has_end_nodes() ? 1 << SAMPLE : 0);
  work->ensure(atom->nlocal, need);
}

/* ---------------------------------------------------------------------- */

PEJump::AtomSet FixPEJumpAsync::group_atoms(const AtomList *only) const
{
  return {groupbit, only};
}

/* ---------------------------------------------------------------------- */

bool FixPEJumpAsync::watch(int when) const
{
  return others->may_change_velocities(when);
}

/* ----------------------------------------------------------------------
   the end of a run: remember the velocities
------------------------------------------------------------------------- */

void FixPEJumpAsync::post_run()
{
  // a change in the last steps of the run has no next coarse node
  if (watch(OtherFixes::BETWEEN_STEPS | OtherFixes::INSIDE_STEP)) {
    if (watch(OtherFixes::BETWEEN_STEPS)) note_velocity_changes(nullptr);
    refuse_velocity_changes();
  }
  scheme->end_run(group_atoms(), nodes->tallied(clocks->at_coarse_node()));
  // the fine clock as the run leaves it (atoms lost through a boundary
  // leave it too), for the next run to compare
  assign->changed();
  assign->report(style);
}

/* ---------------------------------------------------------------------- */

double FixPEJumpAsync::compute_scalar()
{
  return compute_vector(0);
}
