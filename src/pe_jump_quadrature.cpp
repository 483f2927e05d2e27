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

#include "pe_jump_quadrature.h"

#include <cmath>
#include <stdexcept>

using namespace LAMMPS_NS::PEJump;

namespace {

// nodes (in [-1,1], non-negative half, ascending) and weights (summing to 2
// over the whole rule) from the closed forms of the rules

struct HalfRule {
  std::vector<double> x, w;
};

HalfRule legendre_half(int n)
{
  switch (n) {
    case 1:
      return {{0.0}, {2.0}};
    case 2:
      return {{1.0 / std::sqrt(3.0)}, {1.0}};
    case 3:
      return {{0.0, std::sqrt(3.0 / 5.0)}, {8.0 / 9.0, 5.0 / 9.0}};
    case 4: {
      const double r = 2.0 / 7.0 * std::sqrt(6.0 / 5.0);
      const double s = std::sqrt(30.0);
      return {{std::sqrt(3.0 / 7.0 - r), std::sqrt(3.0 / 7.0 + r)},
              {(18.0 + s) / 36.0, (18.0 - s) / 36.0}};
    }
    case 5: {
      const double r = 2.0 * std::sqrt(10.0 / 7.0);
      const double s = 13.0 * std::sqrt(70.0);
      return {{0.0, std::sqrt(5.0 - r) / 3.0, std::sqrt(5.0 + r) / 3.0},
              {128.0 / 225.0, (322.0 + s) / 900.0, (322.0 - s) / 900.0}};
    }
  }
  throw std::invalid_argument("Gauss-Legendre rule needs 1 to 5 points");
}

HalfRule lobatto_half(int n)
{
  switch (n) {
    case 2:
      return {{1.0}, {1.0}};
    case 3:
      return {{0.0, 1.0}, {4.0 / 3.0, 1.0 / 3.0}};
    case 4:
      return {{1.0 / std::sqrt(5.0), 1.0}, {5.0 / 6.0, 1.0 / 6.0}};
    case 5:
      return {{0.0, std::sqrt(3.0 / 7.0), 1.0}, {32.0 / 45.0, 49.0 / 90.0, 1.0 / 10.0}};
  }
  throw std::invalid_argument("Gauss-Lobatto rule needs 2 to 5 points");
}

}    // namespace

/* ---------------------------------------------------------------------- */

Quadrature::Quadrature(Family family, int npoints, bool centre_node) : fam(family), npts(npoints)
{
  const HalfRule half = (family == LEGENDRE) ? legendre_half(npoints) : lobatto_half(npoints);

  // mirror the half rule onto [-1,1] and map to [0,1] (s = (1+x)/2, weight w/2);
  // upper nodes are computed as 1 - s so that the rule is exactly symmetric

  const int nhalf = static_cast<int>(half.x.size());
  const int first = (half.x[0] == 0.0) ? 1 : 0;
  for (int k = nhalf - 1; k >= first; --k) {
    node.push_back(0.5 * (1.0 - half.x[k]));
    weight.push_back(0.5 * half.w[k]);
  }
  if (first) {
    node.push_back(0.5);
    weight.push_back(0.5 * half.w[0]);
  } else if (centre_node) {
    node.push_back(0.5);
    weight.push_back(0.0);
  }
  for (int k = first; k < nhalf; ++k) {
    node.push_back(1.0 - 0.5 * (1.0 - half.x[k]));
    weight.push_back(0.5 * half.w[k]);
  }
}

/* ---------------------------------------------------------------------- */

int Quadrature::primary() const
{
  if (node.back() == 1.0) return size() - 1;
  return size() / 2;
}

/* ---------------------------------------------------------------------- */

bool Quadrature::primary_off_centre() const
{
  const Quadrature proper(fam, npts);
  const double at = proper.node[proper.primary()];
  return (at != 0.5) && (at != 1.0);
}

/* ---------------------------------------------------------------------- */

bool Quadrature::family_named(const std::string &name, Family &family)
{
  if (name == "lobatto")
    family = LOBATTO;
  else if (name == "legendre")
    family = LEGENDRE;
  else
    return false;
  return true;
}

/* ---------------------------------------------------------------------- */

std::string Quadrature::name() const
{
  if (fam == LEGENDRE && npts == 1) return "midpoint";
  return std::string(fam == LEGENDRE ? "legendre " : "lobatto ") + std::to_string(npts);
}

/* ---------------------------------------------------------------------- */

NestedLobatto::NestedLobatto()
{
  for (const int n : {2, 3, 5}) rules.emplace_back(Quadrature::LOBATTO, n);
  const std::vector<double> &all = finest().node;
  for (const auto &rule : rules) {
    std::vector<int> where;
    for (const double c : rule.node) {
      int k = 0;
      while (std::fabs(all[k] - c) > 1.0e-14) ++k;
      where.push_back(k);
    }
    index.push_back(where);
  }
}

/* ---------------------------------------------------------------------- */

bool NestedLobatto::added(int level, int j) const
{
  if (level == 0) return true;
  for (const int k : index[level - 1])
    if (k == index[level][j]) return false;
  return true;
}
