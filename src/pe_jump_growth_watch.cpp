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

#include "pe_jump_growth_watch.h"

#include <algorithm>

using namespace LAMMPS_NS::PEJump;

/* ---------------------------------------------------------------------- */

void GrowthWatch::restart()
{
  *this = GrowthWatch();
}

/* ---------------------------------------------------------------------- */

void GrowthWatch::sample(double pseudo_kinetic, double jump)
{
  jump_sum += jump;
  kinetic_sum += pseudo_kinetic + jump;
  if (++samples < WINDOW) return;
  latest = (kinetic_sum > 0.0) ? jump_sum / kinetic_sum : 0.0;
  // the window LAG before this one joins the reference (the first window
  // never does)
  const int slot = windows % LAG;
  const bool compared = windows - LAG >= 1;
  if (compared) reference = std::max(reference, recent[slot]);
  if (compared && (latest > FACTOR * reference) && (latest > MIN_SHARE)) grown = true;
  recent[slot] = latest;
  windows++;
  samples = 0;
  jump_sum = kinetic_sum = 0.0;
}
