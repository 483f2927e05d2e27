/* -*- c++ -*- ----------------------------------------------------------
   LAMMPS - Large-scale Atomic/Molecular Massively Parallel Simulator
   https://www.lammps.org/, Sandia National Laboratories
   LAMMPS development team: developers@lammps.org

   Copyright (2003) Sandia Corporation.  Under the terms of Contract
   DE-AC04-94AL85000 with Sandia Corporation, the U.S. Government retains
   certain rights in this software.  This software is distributed under
   the GNU General Public License.

   See the README file in the top-level LAMMPS directory.
------------------------------------------------------------------------- */

#ifndef LMP_PE_JUMP_AUTO_QUADRATURE_H
#define LMP_PE_JUMP_AUTO_QUADRATURE_H

#include "pe_jump_atom_set.h"
#include "pe_jump_quadrature.h"
#include "pointers.h"

#include <string>

namespace LAMMPS_NS {
namespace PEJump {
  class NodeSampler;

  // quadrature auto: per step the first of the nested Gauss-Lobatto rules
  // with 2, 3 and 5 points whose pseudo-energy defect is within the
  // tolerance. The start node is the previous end node, the end node the
  // Verlet evaluation, which also tallies the potential energy V(q^{n+1})
  // (a compute pe asks for it at every step). The defect of a rule is then
  // known before the jump: D = V(q^{n+1}) - V(q^n) + h sum_i v_i^{n+1/2} . I_i,
  // I the rule's quadrature average of the forces.

  class AutoQuadrature : protected Pointers {
   public:
    AutoQuadrature(class LAMMPS *, const std::string &fix_id, double tol);
    ~AutoQuadrature() override;

    void create_compute();                          // post_constructor()
    void check_compute(const char *style) const;    // init()
    void start_run(NodeSampler &, int mask);        // setup(): V(q^n)

    // fsum = the average of the first rule within the tolerance, from the
    // start and end node forces fstart and fend, for steps of size h with
    // free-flight velocities v; returns the nodes evaluated
    int sum(NodeSampler &, int mask, const AtomSet &, const FreeFlight &v, double h,
            double **fstart, double **fend, double **fsum);

    // post_run(): steps taken with each rule (nothing if no step was taken)
    void report(const char *style);
    double memory_usage() const { return 3.0 * sizeof(double) * nfnode; }

   private:
    NestedLobatto rules;
    double tol;
    std::string id_pe;    // the compute pe
    double vprev;         // V(q^n)
    bigint steps[3];      // steps taken with each rule in this run
    double **fnode;       // forces at the nodes a finer rule takes again
    int nfnode;
    double defect(const AtomSet &, const FreeFlight &, double h, double dv, double **fsum) const;
  };

}    // namespace PEJump
}    // namespace LAMMPS_NS

#endif
