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

#ifndef LMP_PE_JUMP_QUADRATURE_H
#define LMP_PE_JUMP_QUADRATURE_H

#include <cmath>
#include <string>
#include <vector>

namespace LAMMPS_NS {
namespace PEJump {

  // Symmetric quadrature rule on the unit interval [0,1]:
  // int_0^1 f(s) ds ~ sum_k weight[k] f(node[k]), nodes in ascending order.
  // Gauss-Legendre with N points is exact for polynomials of degree 2N-1,
  // Gauss-Lobatto with N points (both ends are nodes) for degree 2N-3.

  class Quadrature {
   public:
    enum Family { LEGENDRE, LOBATTO };

    static constexpr int MAX_POINTS = 5;

    // centre_node: a Gauss-Legendre rule with an even number of points gets
    // the centre 1/2 as an extra node of weight 0, which then is the primary
    // node (where forces that are not integrated by the rule are taken)
    Quadrature(Family family, int npoints, bool centre_node = false);

    // the family of a rule's name in the input ("lobatto", "legendre"):
    // false if there is none; the fewest points of a family
    static bool family_named(const std::string &name, Family &family);
    static int min_points(Family family) { return (family == LOBATTO) ? 2 : 1; }

    Family family() const { return fam; }
    int points() const { return npts; }    // points of the rule proper
    int size() const { return static_cast<int>(node.size()); }
    int degree() const { return fam == LEGENDRE ? 2 * npts - 1 : 2 * npts - 3; }
    std::string name() const;

    // true if the first node is the start of the interval and the last its end,
    // so that the end node of one step is the start node of the next
    bool has_end_nodes() const { return (node.front() == 0.0) && (node.back() == 1.0); }
    // every node is a step end (lobatto 2): atoms of another time
    // integrator may then interact with the atoms of the rule
    bool only_end_nodes() const { return has_end_nodes() && (size() == 2); }
    // the primary node of the rule proper is neither the centre nor the
    // end of the step, where an impulse at the primary node must sit (the
    // constructor's centre_node then adds the centre)
    bool primary_off_centre() const;

    // the start node is the previous step's end node: its forces are kept
    // from there (fstart) instead of sampled again
    bool reuses_start_node() const { return has_end_nodes(); }
    // the first node that is sampled (after a reused start node)
    int first_sampled() const { return reuses_start_node() ? 1 : 0; }

    // the terms of the quadrature sum known once the primary node is
    // evaluated, for one atom: sum = w_p fp (+ w_0 fstart with a reused
    // start node, whose forces then become fp, the next step's start; an
    // unset start, NaN, takes fp); onto: added to the other nodes' terms
    // in sum
    struct StartSum {
      double wp, w0;
      bool reuse, onto;
      void operator()(const double *fp, double *fstart, double *sum) const
      {
        if (reuse && std::isnan(fstart[0]))
          for (int k = 0; k < 3; k++) fstart[k] = fp[k];
        for (int k = 0; k < 3; k++) {
          sum[k] = onto ? sum[k] + wp * fp[k] : wp * fp[k];
          if (reuse) {
            sum[k] += w0 * fstart[k];
            fstart[k] = fp[k];
          }
        }
      }
    };
    StartSum start_sum(bool onto = false) const
    {
      return {weight[primary()], weight[0], reuses_start_node(), onto};
    }

    // node used for the force evaluation that the MD loop does anyway:
    // the step end if it is a node, else the middle (or first past the
    // middle) node
    int primary() const;

    std::vector<double> node, weight;

   private:
    Family fam;
    int npts;
  };

  // quadrature auto: the nested Gauss-Lobatto rules with 2, 3 and 5 points.
  // The nodes of each rule are among those of the next, so a step that
  // needs a finer rule evaluates only the nodes it adds; every node is
  // named by its index in the finest rule.

  class NestedLobatto {
   public:
    NestedLobatto();

    int levels() const { return static_cast<int>(rules.size()); }
    const Quadrature &rule(int level) const { return rules[level]; }
    const Quadrature &finest() const { return rules.back(); }

    // index in the finest rule of node j of the rule of this level
    int finest_index(int level, int j) const { return index[level][j]; }

    // true if node j of this level is not a node of the level before
    bool added(int level, int j) const;

   private:
    std::vector<Quadrature> rules;
    std::vector<std::vector<int>> index;
  };

}    // namespace PEJump
}    // namespace LAMMPS_NS

#endif
