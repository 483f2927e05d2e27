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

#include "pe_jump_auto_quadrature.h"

#include "atom.h"
#include "comm.h"
#include "compute.h"
#include "error.h"
#include "memory.h"
#include "modify.h"
#include "pe_jump_errors.h"
#include "pe_jump_force_sampler.h"
#include "pe_jump_node_sampler.h"
#include "update.h"

#include <cmath>
#include <memory>

using namespace LAMMPS_NS;
using namespace LAMMPS_NS::PEJump;

/* ---------------------------------------------------------------------- */

AutoQuadrature::AutoQuadrature(LAMMPS *lmp, const std::string &fix_id, double tolerance) :
    Pointers(lmp), tol(tolerance), id_pe(fix_id + "_pe"), vprev(0.0), steps{0, 0, 0},
    fnode(nullptr), nfnode(0)
{
}

/* ---------------------------------------------------------------------- */

AutoQuadrature::~AutoQuadrature()
{
  memory->destroy(fnode);
  if (modify->get_compute_by_id(id_pe)) modify->delete_compute(id_pe);
}

/* ---------------------------------------------------------------------- */

void AutoQuadrature::create_compute()
{
  modify->add_compute(fmt::format("{} all pe", id_pe));
}

/* ---------------------------------------------------------------------- */

void AutoQuadrature::check_compute(const char *style) const
{
  if (!modify->get_compute_by_id(id_pe))
    error->all(FLERR, "Fix {}: compute {} was deleted{}", style, id_pe, errorurl(16));
}

/* ---------------------------------------------------------------------- */

void AutoQuadrature::start_run(NodeSampler &nodes, int mask)
{
  vprev = nodes.potential(mask);
  modify->get_compute_by_id(id_pe)->addstep(update->ntimestep + 1);
}

/* ---------------------------------------------------------------------- */

int AutoQuadrature::sum(NodeSampler &nodes, int mask, const AtomSet &set, const FreeFlight &v,
                        double h, double **fstart, double **fend, double **fsum)
{
  ForceSampler *sampler = nodes.forces();
  const double vnew = (update->eflag_global == update->ntimestep) ? sampler->energy(mask)
                                                                  : nodes.potential(mask);
  const double dv = vnew - vprev;
  vprev = vnew;
  modify->get_compute_by_id(id_pe)->addstep(update->ntimestep + 1);
  if (atom->nlocal > nfnode) {
    nfnode = atom->nlocal + atom->nlocal / 16 + 64;
    memory->destroy(fnode);
    memory->create(fnode, nfnode, 3, "pe_jump:fnode");
  }

  // forces at node j of a level's rule: kept ones (the end nodes, a node
  // of a coarser level), or evaluated now. The rule decides, the same on
  // every rank (a rank without atoms has no arrays: deciding from them, it
  // alone evaluated forces while the others reduced the defect, a hang)
  double **f = atom->f;
  const auto evaluate_now = [&](int level, int j) {
    const double c = rules.rule(level).node[j];
    return (c != 0.0) && (c != 1.0) && rules.added(level, j);
  };
  const auto kept = [&](int level, int j) -> double ** {
    const double c = rules.rule(level).node[j];
    if (c == 0.0) return fstart;
    return (c == 1.0) ? fend : fnode;
  };
  int level = 0, evaluated = 0;
  std::unique_ptr<NodeSampler::Keep> keep;
  while (true) {
    const Quadrature &r = rules.rule(level);
    const bool last = (level + 1 == rules.levels());
    set.each(atom->mask, atom->nlocal, [&](int i) {
      for (int k = 0; k < 3; k++) fsum[i][k] = 0.0;
    });
    for (int j = 0; j < r.size(); j++) {
      double **fj = kept(level, j);
      if (evaluate_now(level, j)) {
        if (!keep) keep = std::make_unique<NodeSampler::Keep>(nodes, NodeSampler::ALL_OWNED);
        nodes.evaluate_at((r.node[j] - 1.0) * h, v, set, mask);
        ++evaluated;
        fj = f;
        if (!last)
          set.each(atom->mask, atom->nlocal, [&](int i) {
            for (int k = 0; k < 3; k++) fnode[i][k] = f[i][k];
          });
      }
      const double w = r.weight[j];
      set.each(atom->mask, atom->nlocal, [&](int i) {
        for (int k = 0; k < 3; k++) fsum[i][k] += w * fj[i][k];
      });
    }
    if (last || (defect(set, v, h, dv, fsum) <= tol)) break;
    ++level;
  }
  ++steps[level];
  return evaluated;
}

/* ---------------------------------------------------------------------- */

double AutoQuadrature::defect(const AtomSet &set, const FreeFlight &v, double h, double dv,
                              double **fsum) const
{
  double local = 0.0, global = 0.0;
  set.each(atom->mask, atom->nlocal, [&](int i) {
    local += v(i, 0) * fsum[i][0] + v(i, 1) * fsum[i][1] + v(i, 2) * fsum[i][2];
  });
  MPI_Allreduce(&local, &global, 1, MPI_DOUBLE, MPI_SUM, world);
  return fabs(dv + h * global);
}

/* ---------------------------------------------------------------------- */

void AutoQuadrature::report(const char *style)
{
  // (a run of 0 steps, or a rerun, integrated nothing)
  if ((comm->me == 0) && (steps[0] + steps[1] + steps[2] > 0))
    utils::logmesg(lmp,
                   "Fix {} quadrature auto {}: steps with lobatto 2: {}, lobatto 3: {}, "
                   "lobatto 5: {}\n",
                   style, tol, steps[0], steps[1], steps[2]);
  steps[0] = steps[1] = steps[2] = 0;
}
