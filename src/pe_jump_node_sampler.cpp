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

#include "pe_jump_node_sampler.h"

#include "atom.h"
#include "bond.h"
#include "comm.h"
#include "compute.h"
#include "dump.h"
#include "error.h"
#include "force.h"
#include "memory.h"
#include "modify.h"
#include "output.h"
#include "pe_jump_errors.h"
#include "pe_jump_force_sampler.h"
#include "pe_jump_quadrature.h"
#include "update.h"
#include "utils.h"

#include <cstring>

using namespace LAMMPS_NS;
using namespace LAMMPS_NS::PEJump;

/* ---------------------------------------------------------------------- */

NodeSampler::NodeSampler(LAMMPS *lmp, ForceSampler *forces) :
    Pointers(lmp), sampler(forces), xkept(nullptr), fkept(nullptr), nkept(0), keeping(false),
    keep_on_move(false), shift_time(false), ghosts_away(false), eflag_step(0), vflag_step(0)
{
}

/* ---------------------------------------------------------------------- */

NodeSampler::~NodeSampler()
{
  memory->destroy(xkept);
  memory->destroy(fkept);
}

/* ---------------------------------------------------------------------- */

void NodeSampler::make_room()
{
  if (atom->nlocal <= nkept) return;
  nkept = atom->nlocal + atom->nlocal / 16 + 64;
  memory->destroy(xkept);
  memory->destroy(fkept);
  memory->create(xkept, nkept, 3, "pe_jump:xkept");
  memory->create(fkept, nkept, 3, "pe_jump:fkept");
}

/* ----------------------------------------------------------------------
   keep the forces of the owned atoms, and the positions of all owned atoms
   or of those listed. The ghosts are not kept: the forward communication
   of the next force evaluation brings them up to date.
------------------------------------------------------------------------- */

NodeSampler::Keep::Keep(NodeSampler &sampler, Positions positions, const AtomList *atoms,
                        bool keep_forces, const AtomList *nonzero_forces) :
    nodes(sampler),
    which(positions), list(atoms), forces(keep_forces), touched(sampler.sampler->touches()),
    nonzero(nonzero_forces)
{
  if (nodes.keeping) nodes.error->one(FLERR, "Fix pe_jump: nested NodeSampler::Keep (bug)");
  nodes.keeping = true;
  nodes.make_room();
  const size_t nbytes = 3 * sizeof(double) * nodes.atom->nlocal;
  if (!nbytes) return;
  if (forces) copy_forces(nodes.atom->f, nodes.fkept);
  double **x = nodes.atom->x;
  if (which == ALL_OWNED) memcpy(&nodes.xkept[0][0], &x[0][0], nbytes);
  if (which == LISTED)
    for (const int i : *list)
      for (int k = 0; k < 3; k++) nodes.xkept[i][k] = x[i][k];
  nodes.keep_on_move = (which == SET_ON_MOVE);
}

/* ---------------------------------------------------------------------- */

NodeSampler::Keep::~Keep()
{
  nodes.keeping = false;
  // (SET_ON_MOVE without a move: the positions are those kept)
  const bool moved = !nodes.keep_on_move;
  nodes.keep_on_move = false;
  const size_t nbytes = 3 * sizeof(double) * nodes.atom->nlocal;
  if (!nbytes) return;
  double **x = nodes.atom->x;
  if ((which == ALL_OWNED) || ((which == SET_ON_MOVE) && moved && !list))
    memcpy(&x[0][0], &nodes.xkept[0][0], nbytes);
  if ((which == LISTED) || ((which == SET_ON_MOVE) && moved && list))
    for (const int i : *list)
      for (int k = 0; k < 3; k++) x[i][k] = nodes.xkept[i][k];
  if (forces) copy_forces(nodes.fkept, nodes.atom->f);
}

/* ---------------------------------------------------------------------- */

void NodeSampler::Keep::forces_back()
{
  if (forces && nodes.atom->nlocal) copy_forces(nodes.fkept, nodes.atom->f);
  forces = false;
}

/* ----------------------------------------------------------------------
   the forces of the owned atoms that the sampler may change (all of them
   unless it touches a part only)
------------------------------------------------------------------------- */

void NodeSampler::Keep::copy_forces(double **from, double **to) const
{
  if (!touched && nonzero) {
    // (putting back: the others' forces were zero)
    if (from == nodes.fkept) memset(&to[0][0], 0, 3 * sizeof(double) * nodes.atom->nlocal);
    for (const int i : *nonzero)
      for (int k = 0; k < 3; k++) to[i][k] = from[i][k];
    return;
  }
  if (!touched) {
    memcpy(&to[0][0], &from[0][0], 3 * sizeof(double) * nodes.atom->nlocal);
    return;
  }
  if (touched->nfirst > 0) memcpy(&to[0][0], &from[0][0], 3 * sizeof(double) * touched->nfirst);
  for (const int i : *touched->after)
    for (int k = 0; k < 3; k++) to[i][k] = from[i][k];
}

/* ---------------------------------------------------------------------- */

void NodeSampler::evaluate_at(double shift, const FreeFlight &v, const AtomSet &set, int mask)
{
  double **x = atom->x;
  if (keep_on_move) {
    set.each(atom->mask, atom->nlocal, [&](int i) {
      for (int k = 0; k < 3; k++) {
        xkept[i][k] = x[i][k];
        x[i][k] = xkept[i][k] + shift * v(i, k);
      }
    });
    keep_on_move = false;
  } else {
    set.each(atom->mask, atom->nlocal, [&](int i) {
      for (int k = 0; k < 3; k++) x[i][k] = xkept[i][k] + shift * v(i, k);
    });
  }
  const double now = update->atime;
  if (shift_time) update->atime = now + shift;
  sampler->compute(mask, 0, 0);
  update->atime = now;
  ghosts_away = true;    // the evaluation brought the ghosts to the node
}

/* ---------------------------------------------------------------------- */

int NodeSampler::sum_nodes(const Quadrature &rule, int first, int skip, double scale, double offset,
                           const FreeFlight &v, const AtomSet &set, int mask, double **acc,
                           double **fend, bool keep_forces)
{
  // the positions are kept as the first node moves the atoms of set; a set
  // of a group other than all keeps every owned atom before (and puts every
  // one back)
  Keep keep(*this, positions_for(set), set.list, keep_forces);
  return sum_nodes_in(keep, rule, first, skip, scale, offset, v, set, mask, acc, fend, true);
}

/* ---------------------------------------------------------------------- */

int NodeSampler::sum_nodes_in(Keep & /*keep*/, const Quadrature &rule, int first, int skip,
                              double scale, double offset, const FreeFlight &v, const AtomSet &set,
                              int mask, double **acc, double **fend, bool onto_acc)
{
  const int last = rule.size() - 1;
  int evaluated = 0;
  for (int node = first; node <= last; node++) {
    if (node == skip) continue;
    evaluate_at(scale * rule.node[node] + offset, v, set, mask);
    add_node(rule.weight[node], set, acc, !onto_acc && !evaluated, (node == last) ? fend : nullptr);
    ++evaluated;
  }
  return evaluated;
}

/* ---------------------------------------------------------------------- */

int NodeSampler::walk_nodes(const Quadrature &rule, int first, int last, double scale, double from,
                            const FreeFlight &v, const AtomSet &set, int mask, double **acc)
{
  double *x = flat(atom->x);
  double at = from;
  for (int node = first; node <= last; node++) {
    const double dt = scale * rule.node[node] - at;
    // (a step begun ahead has its atoms at the first node already)
    if (dt != 0.0)
      set.each(atom->mask, atom->nlocal, [&](int i) {
        for (int k = 0; k < 3; k++) x[3 * i + k] += dt * v(i, k);
      });
    at = scale * rule.node[node];
    sampler->compute(mask, 0, 0);
    ghosts_away = true;
    add_node(rule.weight[node], set, acc, node == first, nullptr);
  }
  return MAX(last - first + 1, 0);
}

/* ---------------------------------------------------------------------- */

void NodeSampler::add_node(double w, const AtomSet &set, double **acc, bool replace,
                           double **fend) const
{
  // (the atoms of a fine step lie scattered: see flat())
  const double *f = flat(atom->f);
  double *sum = flat(acc), *end = flat(fend);
  const auto add = [&](int i) {
    for (int k = 3 * i; k < 3 * i + 3; k++) sum[k] += w * f[k];
    if (end)
      for (int k = 3 * i; k < 3 * i + 3; k++) end[k] = f[k];
  };
  const auto set_to = [&](int i) {
    for (int k = 3 * i; k < 3 * i + 3; k++) sum[k] = w * f[k];
    if (end)
      for (int k = 3 * i; k < 3 * i + 3; k++) end[k] = f[k];
  };
  if (replace)
    set.each(atom->mask, atom->nlocal, set_to);
  else
    set.each(atom->mask, atom->nlocal, add);
}

/* ---------------------------------------------------------------------- */

double NodeSampler::potential(int mask)
{
  Keep keep(*this);
  sampler->compute(mask, ENERGY_GLOBAL, 0);
  return sampler->energy(mask);
}

/* ---------------------------------------------------------------------- */

NodeSampler::Tallied NodeSampler::tallied(bool at_positions) const
{
  Tallied now = {at_positions && (update->eflag_global == update->ntimestep), 0.0, 0.0};
  if (now.known) now.energy = sampler->energy(ForceSampler::ALL, &now.magnitude);
  return now;
}

/* ---------------------------------------------------------------------- */

void NodeSampler::ask_energy_at(bigint step) const
{
  Compute *pe = modify->get_compute_by_id("thermo_pe");
  if (pe) pe->addstep(step);
}

/* ---------------------------------------------------------------------- */

double NodeSampler::memory_usage() const
{
  return 2.0 * nkept * 3 * sizeof(double);
}

/* ---------------------------------------------------------------------- */

double NodeSampler::at_step_end(bool observed, int groupbit, bool tallied)
{
  if (!tallied && (step_tallies() || forces_dumped())) {
    const int *mask = atom->mask;
    double **f = atom->f;
    std::vector<double> others;    // forces of the atoms outside the group
    if (groupbit)
      for (int i = 0; i < atom->nlocal; i++)
        if (!(mask[i] & groupbit)) others.insert(others.end(), f[i], f[i] + 3);
    sampler->compute(ForceSampler::ALL, eflag_step, vflag_step);
    if (groupbit) {
      f = atom->f;
      size_t n = 0;
      for (int i = 0; i < atom->nlocal; i++)
        if (!(mask[i] & groupbit))
          for (int k = 0; k < 3; k++) f[i][k] = others[n++];
    }
    ghosts_away = false;
    return 1.0;
  }
  if (observed || (tallied && ghosts_away)) comm->forward_comm();
  ghosts_away = false;
  return 0.0;
}

/* ----------------------------------------------------------------------
   true if a dump that may write per-atom forces writes at this step (all
   styles but those of positions only, pictures and local or grid data)
------------------------------------------------------------------------- */

bool NodeSampler::forces_dumped() const
{
  const auto without_forces = [](const char *style) {
    for (const char *pattern :
         {"^atom", "^xyz", "^dcd", "^xtc", "^image", "^movie", "^local", "^grid"})
      if (utils::strmatch(style, pattern)) return true;
    return false;
  };
  for (int i = 0; i < output->ndump; i++)
    if ((output->next_dump[i] == update->ntimestep) && !without_forces(output->dump[i]->style))
      return true;
  return false;
}

/* ----------------------------------------------------------------------
   what an evaluation of the force field changes besides the forces, where
   the fix evaluates it twice on output steps (at the primary node inside
   the step and at the step end, at_step_end()): the computes of the TALLY
   package add up the pair tallies of every evaluation in a step (they
   would count pairs twice), and bonds that break inside their evaluation
   (bond styles with partial_flag) would break where output looks (the
   trajectory would depend on the output)
------------------------------------------------------------------------- */

void NodeSampler::refuse_step_end_side_effects(const char *style, const std::string &why) const
{
  for (auto *compute : modify->get_compute_list())
    if (utils::strmatch(compute->style, "/tally$"))
      error->all(FLERR,
                 "Fix {}: compute {} ({}) adds up the pair tallies of every force evaluation "
                 "in a step, and {}{}",
                 style, compute->id, compute->style, why, errorurl(34));
  // (peridynamic bonds are refused before, ForceSampler::refuse_stateful_forces)
  if (force->bond && force->bond->partial_flag)
    error->all(FLERR,
               "Fix {}: the bonds of bond style {} break inside the force evaluation, and {}{}",
               style, force->bond_style, why, errorurl(33));
}

/* ---------------------------------------------------------------------- */

void NodeSampler::ghosts_with_owned(bool observed)
{
  if (ghosts_away && observed) comm->forward_comm();
  ghosts_away = false;
}

/* ---------------------------------------------------------------------- */

bool NodeSampler::energy_only_step() const
{
  const bigint now = update->ntimestep;
  return (update->eflag_global == now) && (update->eflag_atom != now) &&
      (update->vflag_global != now) && (update->vflag_atom != now) && !forces_dumped();
}

/* ---------------------------------------------------------------------- */

bool NodeSampler::tally_step() const
{
  const bigint now = update->ntimestep;
  return (update->eflag_global == now) || (update->eflag_atom == now) ||
      (update->vflag_global == now) || (update->vflag_atom == now);
}
