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

#ifndef LMP_PE_JUMP_REACH_BOUND_H
#define LMP_PE_JUMP_REACH_BOUND_H

#include "lmptype.h"

#include <cmath>

namespace LAMMPS_NS {
namespace PEJump {

  // An upper bound on how far the atoms of a set are from their positions
  // at the last neighbor list build: the largest distance of the last
  // exact measure plus what the atoms can have moved since (moved(), at
  // most their largest speed times the time, see StabilityGuard::travel).
  // While it is within a limit, a measure against that limit can be
  // skipped: its verdict is known. A list build since the measure (the
  // count Neighbor::ncalls) or forget() asks for a measure again.
  class ReachBound {
   public:
    void forget() { known = false; }
    void moved(double distance) { reach += distance; }
    bool within(double limit, bigint builds) const
    {
      return known && (builds == builds_then) && (reach < limit);
    }
    // an exact measure: the largest distance is at most distance
    void measured(double distance, bigint builds)
    {
      reach = distance;
      known = std::isfinite(distance);
      builds_then = builds;
    }

   private:
    bool known = false;
    double reach = 0.0;
    bigint builds_then = -1;
  };

}    // namespace PEJump
}    // namespace LAMMPS_NS

#endif
