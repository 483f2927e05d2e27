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

#include "pe_jump_other_fixes.h"

#include "atom.h"
#include "comm.h"
#include "error.h"
#include "force.h"
#include "modify.h"
#include "neigh_list.h"
#include "neighbor.h"
#include "output.h"
#include "pair.h"
#include "pe_jump_errors.h"
#include "pe_jump_force_sampler.h"
#include "pe_jump_step_variables.h"
#include "update.h"

#include <map>

using namespace LAMMPS_NS;
using namespace LAMMPS_NS::PEJump;
using namespace FixConst;

// What only a fix's style name tells (LAMMPS has no flag for it), one row
// per trait: the styles as patterns of utils::strmatch()
namespace {
enum Trait {
  LANGEVIN,               // fix langevin (and its variants)
  TTM,                    // two-temperature models: thermostats without ecouple_flag
  ENFORCE2D,              // zeroes z components
  INITIAL_BOOKKEEPING,    // acts in initial_integrate without moving atoms
  REFLECTS,               // reflecting walls
  REVERSES,               // fixes that reverse velocities
  INSERTS_INTO_GROUP,     // inserts atoms with the fix group's bit
  INSERTS_INTO_ALL,       // inserts atoms with the bit of "all" only
  OWN_STEP_COUNT,         // forces follow a count of steps of the fix's own
  READS_ONLY,             // averages, output, group updates, load balance
  REPLACES_FORCES,        // set, average or project forces
  ADAPTS,                 // fix adapt
  VARIABLE_FORCES         // add forces that variables may give
};
const std::map<Trait, std::vector<const char *>> NAMED = {
    {LANGEVIN, {"^langevin"}},
    {TTM, {"^ttm"}},
    {ENFORCE2D, {"^enforce2d"}},
    {INITIAL_BOOKKEEPING, {"^ti/spring", "^dummy"}},
    {REFLECTS, {"^wall/reflect"}},
    {REVERSES, {"^wall/reflect", "^oneway"}},
    {INSERTS_INTO_GROUP, {"^deposit", "^pour", "^gcmc", "^charge/regulation", "^bond/react"}},
    {INSERTS_INTO_ALL, {"^append/atoms"}},
    {OWN_STEP_COUNT, {"^smd", "^ti/spring", "^restrain"}},
    {READS_ONLY,
     {"^ave/", "^print$", "^vector$", "^store/state$", "^halt$", "^GROUP$", "^balance$"}},
    {REPLACES_FORCES,
     {"^setforce", "^aveforce", "^freeze", "^lineforce", "^planeforce", "^enforce2d"}},
    {ADAPTS, {"^adapt"}},
    {VARIABLE_FORCES, {"^addforce", "^efield", "^gravity", "^indent", "^wall/"}}};

bool is(const Fix *fix, Trait trait)
{
  for (const char *pattern : NAMED.at(trait))
    if (utils::strmatch(fix->style, pattern)) return true;
  return false;
}
}    // namespace

/* ---------------------------------------------------------------------- */

OtherFixes::OtherFixes(LAMMPS *lmp, Fix *fix) :
    Pointers(lmp), self(fix), nadders(0), nthermostats(0), nforcing(0), others_bits(0), hooks(0)
{
}

/* ----------------------------------------------------------------------
   fixes that replace or project forces act at every quadrature node, those
   that add forces act once per step as impulses. Constraints are refused,
   other time integrators are remembered for the interaction check
------------------------------------------------------------------------- */

void OtherFixes::sort(ForceSampler &sampler)
{
  std::vector<Fix *> preparations, projections;
  nadders = nthermostats = nforcing = others_bits = hooks = 0;
  end_of_step_every.clear();
  for (auto *ifix : modify->get_fix_list()) {
    if (ifix == self) continue;
    const int mask = ifix->setmask();
    if (mask & END_OF_STEP) end_of_step_every.push_back(MAX(ifix->nevery, 1));
    if (mask & PRE_FORCE) preparations.push_back(ifix);
    // the fixes that replace or project forces leave velocities alone (fix
    // enforce2d zeroes the z velocity, which is zero in a 2d run anyway), as
    // do those that only read the atoms
    const bool projects = (mask & POST_FORCE) && replaces_forces(ifix);
    if (!projects && !reads_only(ifix)) hooks |= mask & (BETWEEN_STEPS | INSIDE_STEP);
    if (ifix->time_integrate) {
      others_bits |= ifix->groupbit;
      continue;
    }
    if (ifix->dof_flag)
      error->all(FLERR, "Fix {} cannot be combined with the constraints of fix {} ({}){}",
                 self->style, ifix->id, ifix->style, errorurl(24));
    // of the langevin fixes only the GJF variant acts before the step
    if (is(ifix, LANGEVIN) && (mask & INITIAL_INTEGRATE))
      error->all(FLERR,
                 "Fix {} cannot be combined with fix {} ({}) with keyword gjf. Use fix langevin "
                 "without gjf, or fix nve{}",
                 self->style, ifix->id, ifix->style, errorurl(25));
    // a thermostat anywhere in the system: the run does not conserve energy
    if (ifix->ecouple_flag || is(ifix, TTM)) {
      ++nthermostats;
      if (mask & POST_FORCE) ++nforcing;
    }
    // fix enforce2d zeroes z components that the force field of a 2d run
    // gives as zero (every z is 0): at the fix's own evaluations it acts
    // only where the atoms carry rotation (omega, angmom, torque), not at
    // the cost of a pass over all atoms at every one of them
    const bool rotation = atom->omega_flag || atom->angmom_flag || atom->torque_flag;
    if (projects && !rotation && is(ifix, ENFORCE2D)) continue;
    if (projects)
      projections.push_back(ifix);
    else if (mask & POST_FORCE)
      ++nadders;
  }
  sampler.set_hooks(preparations, projections);
}

/* ----------------------------------------------------------------------
   fixes that add forces act at the primary node: with a rule whose primary
   node is inside the step, the energy they add to pe (fix_modify energy
   yes) is taken there, half a step before the step end where the force
   field's energy is tallied (first order in the time step)
------------------------------------------------------------------------- */

void OtherFixes::warn_energy_inside_step(const std::string &rule_name, bool primary_at_end)
{
  if (primary_at_end || (comm->me != 0)) return;
  const std::string fixes = named([](Fix *fix) {
    return (fix->setmask() & POST_FORCE) && fix->thermo_energy && fix->energy_global_flag &&
        !replaces_forces(fix);
  });
  if (!fixes.empty())
    warn_once(fmt::format("Fix {} with quadrature {}: the energy of {} (fix_modify energy yes) is "
                          "taken inside the step: first order in the time step{}",
                          self->style, rule_name, fixes, errorurl(37)));
}

/* ----------------------------------------------------------------------
   fix langevin's drag acts at the primary node with the velocity the
   atoms fly with: inside the step (midpoint, odd Legendre rules) that is
   an explicit Euler step of its Ornstein-Uhlenbeck process, whose
   temperature is too high by the factor 1/(1 - gamma h/2) (velocity
   Verlet splits the impulse about the node and has no such term)
------------------------------------------------------------------------- */

void OtherFixes::warn_langevin_inside_step(const std::string &rule_name, bool primary_at_end)
{
  if (primary_at_end || (comm->me != 0)) return;
  const std::string fixes = named([](Fix *fix) {
    return is(fix, LANGEVIN);
  });
  if (!fixes.empty())
    warn_once(fmt::format("Fix {} with quadrature {}: {} acts at the centre of the step: the mean "
                          "temperature comes out high by the fraction dt/(2 damp){}",
                          self->style, rule_name, fixes, errorurl(39)));
}

/* ----------------------------------------------------------------------
   a warning given at init would come again at every run with the same
   settings (twice for run 0 followed by a run)
------------------------------------------------------------------------- */

void OtherFixes::warn_once(const std::string &text)
{
  if (!warned.insert(text).second) return;
  error->warning(FLERR, text);
}

/* ---------------------------------------------------------------------- */

void OtherFixes::refuse_for_rule(const std::string &rule_name, bool primary_at_end,
                                 bool only_end_nodes) const
{
  bool after = false;
  for (auto *ifix : modify->get_fix_list()) {
    if (ifix == self) {
      after = true;
      continue;
    }
    const int mask = ifix->setmask();
    if (!primary_at_end) refuse_inside_step(ifix, rule_name);
    // (fix ti/spring only updates its coupling parameter there)
    const bool moves_atoms =
        (mask & INITIAL_INTEGRATE) && !ifix->time_integrate && !is(ifix, INITIAL_BOOKKEEPING);
    if (!primary_at_end && after && moves_atoms)
      error->all(FLERR,
                 "Fix {} ({}) acts in initial_integrate after fix {}, which leaves the atoms "
                 "inside the step with quadrature {}{}",
                 ifix->id, ifix->style, self->id, rule_name, errorurl(26));
    if (!only_end_nodes && ifix->time_integrate && ifix->box_change)
      error->all(FLERR,
                 "Fix {} with quadrature {}: fix {} ({}) changes the box inside the step while "
                 "it integrates its atoms{}",
                 self->style, rule_name, ifix->id, ifix->style, errorurl(23));
  }
}

/* ----------------------------------------------------------------------
   fixes that do not fit a rule whose force evaluation of the MD step lies
   inside the step (midpoint, Legendre rules)
------------------------------------------------------------------------- */

void OtherFixes::refuse_inside_step(Fix *ifix, const std::string &rule_name) const
{
  const int mask = ifix->setmask();
  // fix langevin acts at the end of the step only with tally yes (gjf is
  // refused in sort())
  if (is(ifix, LANGEVIN) && (mask & END_OF_STEP))
    error->all(FLERR,
               "Fix {} with quadrature {}: fix {} ({}) with keyword tally yes counts the energy "
               "it exchanges as for velocity Verlet{}",
               self->style, rule_name, ifix->id, ifix->style, errorurl(27));
  // fixes whose forces follow a count of steps of their own (a tether that
  // moves by a step's length per force call, a coupling or force constant
  // ramped by the step number): the primary node inside the step would
  // take them at the step's end (first order in the step)
  if (steps_own_clock(ifix))
    error->all(FLERR,
               "Fix {} with quadrature {}: fix {} ({}) sets its forces from its own count of "
               "steps{}",
               self->style, rule_name, ifix->id, ifix->style, errorurl(28));
  // walls that reflect atoms act at the primary node, inside the step: the
  // reflection leaves the atom's jump, which no longer fits its velocity
  // (midpoint: etotal drift 20x fix nve's between static walls; mirroring
  // the jump with the velocity grew the period-2 mode at walls that move
  // until the run stopped), and the stochastic wall takes the time since the
  // crossing from where the step left an atom beyond the wall (lost atoms)
  if (is(ifix, REFLECTS))
    error->all(FLERR,
               "Fix {} with quadrature {}: fix {} ({}) reflects atoms at the node inside the "
               "step{}",
               self->style, rule_name, ifix->id, ifix->style, errorurl(29));
  // fix ttm exchanges energy with the electrons through the velocities at
  // its force call, which lie inside the step here
  if (is(ifix, TTM))
    error->all(FLERR,
               "Fix {} with quadrature {}: fix {} ({}) counts the energy it exchanges with the "
               "electrons from velocities inside the step{}",
               self->style, rule_name, ifix->id, ifix->style, errorurl(30));
}

/* ---------------------------------------------------------------------- */

void OtherFixes::refuse_shared_atoms() const
{
  const int *mask = atom->mask;
  for (auto *ifix : modify->get_fix_list()) {
    if ((ifix == self) || !ifix->time_integrate) continue;
    const int both = self->groupbit | ifix->groupbit;
    bigint local = 0, shared = 0;
    for (int i = 0; i < atom->nlocal; i++)
      if ((mask[i] & both) == both) ++local;
    MPI_Allreduce(&local, &shared, 1, MPI_LMP_BIGINT, MPI_SUM, world);
    if (shared > 0)
      error->all(FLERR,
                 "Fix {} must be the only time integration fix acting on its atoms: {} of them "
                 "are integrated by fix {} ({}) too{}",
                 self->style, shared, ifix->id, ifix->style, errorurl(18));
  }
}

/* ----------------------------------------------------------------------
   atoms inserted during the run start on no list: the check at setup and
   after each list build (refuse_interactions()) sees them only once they
   meet the atoms of the other set, which can be late in the run (LAMMPS'
   deposit example with fix nve on the deposited atoms and quadrature
   lobatto 3 on the substrate: step 400), and two integrators of one
   inserted atom were never seen in the run. Where the input decides,
   refuse here
------------------------------------------------------------------------- */

void OtherFixes::refuse_inserted_atoms(const std::string &rule_name, bool interior) const
{
  std::vector<Fix *> inserters, integrators;
  for (auto *ifix : modify->get_fix_list()) {
    if (ifix == self) continue;
    if (inserted_bits(ifix)) inserters.push_back(ifix);
    if (ifix->time_integrate) integrators.push_back(ifix);
  }
  if (inserters.empty() || integrators.empty()) return;

  // the atoms of this fix (0) and of each other integrator (1, 2, ...) now,
  // and the group bits that gain atoms during the run
  const int nsets = static_cast<int>(integrators.size()) + 1;
  const auto bit_of = [&](int set) {
    return set ? integrators[set - 1]->groupbit : self->groupbit;
  };
  std::vector<bigint> local(nsets, 0), present(nsets, 0);
  const int *mask = atom->mask;
  for (int i = 0; i < atom->nlocal; i++)
    for (int set = 0; set < nsets; set++)
      if (mask[i] & bit_of(set)) ++local[set];
  MPI_Allreduce(local.data(), present.data(), nsets, MPI_LMP_BIGINT, MPI_SUM, world);
  int gaining = 0;
  for (auto *ifix : inserters) gaining |= inserted_bits(ifix);
  const auto populated = [&](int set) {
    return (present[set] > 0) || (gaining & bit_of(set));
  };
  // the pair lists join any two atoms that come close
  const bool pairs = force->pair && (force->pair->cutforce > 0.0);

  for (auto *ifix : inserters) {
    const int bits = inserted_bits(ifix);
    const bool mine = (bits & self->groupbit) != 0;
    for (int set = 1; set < nsets; set++) {
      const Fix *other = integrators[set - 1];
      const bool theirs = (bits & other->groupbit) != 0;
      if (mine && theirs)
        error->all(FLERR,
                   "Fix {} must be the only time integration fix acting on its atoms: fix {} "
                   "({}) inserts atoms into its group and into that of fix {} ({}){}",
                   self->style, ifix->id, ifix->style, other->id, other->style, errorurl(19));
      if (!interior || !pairs) continue;
      if (theirs && populated(0) && !may_be_excluded(bits))
        error->all(FLERR,
                   "Fix {} with quadrature {}: fix {} ({}) inserts atoms that fix {} ({}) "
                   "integrates and that will interact with this fix's atoms{}",
                   self->style, rule_name, ifix->id, ifix->style, other->id, other->style,
                   errorurl(21));
      if (mine && populated(set) && !may_be_excluded(bits))
        error->all(FLERR,
                   "Fix {} with quadrature {}: fix {} ({}) inserts atoms into its group that will "
                   "interact with the atoms of fix {} ({}){}",
                   self->style, rule_name, ifix->id, ifix->style, other->id, other->style,
                   errorurl(22));
    }
  }
}

/* ----------------------------------------------------------------------
   pairs of atoms inserted with the group bits a that neigh_modify exclude
   may leave out of the lists: by type or molecule (the inserting fix
   keeps the types and molecules it inserts to itself) or by a group of
   theirs (which may hold the other set). The check at the list builds
   decides then
------------------------------------------------------------------------- */

bool OtherFixes::may_be_excluded(int a) const
{
  if (!neighbor->exclude) return false;
  if ((neighbor->nex_type > 0) || (neighbor->nex_mol > 0)) return true;
  for (int k = 0; k < neighbor->nex_group; k++)
    if ((a & neighbor->ex1_bit[k]) || (a & neighbor->ex2_bit[k])) return true;
  return false;
}

/* ----------------------------------------------------------------------
   atoms that fixes insert during a run get the group bits of "all" and
   the fix group (deposit, pour, bond/react; gcmc and charge/regulation
   also those of their group keywords, which they keep to themselves),
   those of append/atoms the bit of "all" only. (fix widom deletes its
   test atoms in the step it inserts them)
------------------------------------------------------------------------- */

int OtherFixes::inserted_bits(const Fix *fix)
{
  if (is(fix, INSERTS_INTO_GROUP)) return 1 | fix->groupbit;
  if (is(fix, INSERTS_INTO_ALL)) return 1;
  return 0;
}

/* ----------------------------------------------------------------------
   fixes whose forces follow a count of steps of their own, not the time
   that the nodes carry
------------------------------------------------------------------------- */

bool OtherFixes::steps_own_clock(const Fix *fix)
{
  return is(fix, OWN_STEP_COUNT);
}

/* ----------------------------------------------------------------------
   fixes that read the atoms and never change velocities: averages and
   output (ave/time, ave/atom, ave/chunk, ave/correlate, ave/histo, ...,
   print, vector, store/state, halt), the updates of dynamic groups and
   load balancing (they move atoms between ranks with their velocities)
------------------------------------------------------------------------- */

bool OtherFixes::reads_only(const Fix *fix)
{
  return is(fix, READS_ONLY);
}

/* ---------------------------------------------------------------------- */

bool OtherFixes::reverses_velocities(const Fix *fix)
{
  return is(fix, REVERSES);
}

/* ----------------------------------------------------------------------
   fixes that set, average or project the forces instead of adding to them
------------------------------------------------------------------------- */

bool OtherFixes::replaces_forces(const Fix *fix)
{
  return is(fix, REPLACES_FORCES);
}

/* ---------------------------------------------------------------------- */

std::string OtherFixes::named(const std::function<bool(Fix *)> &keep) const
{
  std::vector<std::string> list;
  for (auto *ifix : modify->get_fix_list())
    if (keep(ifix)) list.push_back(fmt::format("fix {} ({})", ifix->id, ifix->style));
  return utils::join_words(list, ", ");
}

/* ---------------------------------------------------------------------- */

bool OtherFixes::step_observed() const
{
  const bigint now = update->ntimestep;
  if ((now == output->next) || (now == update->laststep)) return true;
  for (const int every : end_of_step_every)
    if (now % every == 0) return true;
  return false;
}

/* ----------------------------------------------------------------------
   the fixes that reverse velocities (reflecting walls, fix oneway), as a
   list for messages ("fix 2 (wall/reflect), fix 3 (oneway)"; empty if none)
------------------------------------------------------------------------- */

std::string OtherFixes::reversing_fixes() const
{
  return named([](Fix *fix) {
    return is(fix, REVERSES);
  });
}

/* ----------------------------------------------------------------------
   fixes that take their forces or force field from variables: those that
   act at every node, and those that add an impulse at the primary node
------------------------------------------------------------------------- */

void OtherFixes::warn_step_number(const std::string &rule_name, bool primary_at_end,
                                  bool only_end_nodes)
{
  if (only_end_nodes || (comm->me != 0)) return;
  // (fix setforce and aveforce, which also act at every node, mostly hold
  // atoms with constants: not named, to keep the warning meaningful)
  const std::string fixes = named([&](Fix *fix) {
    return is(fix, ADAPTS) || (!primary_at_end && is(fix, VARIABLE_FORCES));
  });
  if (fixes.empty()) return;
  const auto names = step_number_variables(lmp);
  if (names.empty()) return;
  warn_once(fmt::format("Fix {}: variable(s) {} read the step number; forces or parameters that "
                        "{} may take from them are first order with quadrature {}{}",
                        self->style, utils::join_words(names, ", "), fixes, rule_name,
                        errorurl(38)));
}

/* ----------------------------------------------------------------------
   atoms of another time integrator (fix nve, fix rigid, a second fix
   pe_jump) sit at the end of the step when forces are computed: forces
   between them and this fix's atoms mix times unless every node of the
   rule is a step end. Checked at setup and after each list build.
------------------------------------------------------------------------- */

void OtherFixes::refuse_interactions(const char *rule_name) const
{
  if (!others_bits) return;
  const int groupbit = self->groupbit;
  const int *mask = atom->mask;
  const auto cross = [&](int i, int j) {
    return ((mask[i] & groupbit) && (mask[j] & others_bits)) ||
        ((mask[i] & others_bits) && (mask[j] & groupbit));
  };
  int local = 0;
  for (int n = 0; (n < neighbor->nlist) && !local; n++) {
    const NeighList *list = neighbor->lists[n];
    // lists of pair styles, built at every reneighboring (others may be stale)
    if (!list || !list->numneigh || list->kokkos || list->occasional ||
        (list->requestor_type != NeighList::PAIR))
      continue;
    for (int ii = 0; (ii < list->inum) && !local; ii++) {
      const int i = list->ilist[ii];
      for (int jj = 0; jj < list->numneigh[i]; jj++)
        if (cross(i, list->firstneigh[i][jj] & NEIGHMASK)) local = 1;
    }
  }
  // bonds, angles, dihedrals, impropers: atoms of both sets in one of them
  // (LAMMPS sets a topology list's length only where the style is defined)
  const auto topology_crosses = [&](bool style, int **list, int n, int natoms) {
    if (!style) return 0;
    for (int m = 0; m < n; m++)
      for (int a = 0; a < natoms; a++)
        for (int b = a + 1; b < natoms; b++)
          if (cross(list[m][a], list[m][b])) return 1;
    return 0;
  };
  if ((atom->molecular != Atom::ATOMIC) && !local)
    local = topology_crosses(force->bond != nullptr, neighbor->bondlist, neighbor->nbondlist, 2) ||
        topology_crosses(force->angle != nullptr, neighbor->anglelist, neighbor->nanglelist, 3) ||
        topology_crosses(force->dihedral != nullptr, neighbor->dihedrallist,
                         neighbor->ndihedrallist, 4) ||
        topology_crosses(force->improper != nullptr, neighbor->improperlist,
                         neighbor->nimproperlist, 4);
  int global = 0;
  MPI_Allreduce(&local, &global, 1, MPI_INT, MPI_MAX, world);
  if (global)
    error->all(FLERR,
               "Fix {} with quadrature {}: atoms of another time integrator interact with its "
               "atoms at step {}{}",
               self->style, rule_name, update->ntimestep, errorurl(20));
}
