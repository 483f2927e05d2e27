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

#include "pe_jump_parasitic_damping.h"

#include "comm.h"
#include "lammps.h"
#include "pe_jump_atom_state.h"
#include "update.h"
#include "utils.h"

#include <algorithm>
#include <string>

using namespace LAMMPS_NS;
using namespace LAMMPS_NS::PEJump;

/* ---------------------------------------------------------------------- */

ParasiticDamping::ParasiticDamping(AtomState &table) : state(table) {}

/* ---------------------------------------------------------------------- */

void ParasiticDamping::allocate()
{
  if (allocated()) return;
  impulse_field = state.add("damp_impulse", 3, std::nan(""));
  difference_field = state.add("damp_difference", 3, std::nan(""));
}

/* ---------------------------------------------------------------------- */

void ParasiticDamping::forget(int i)
{
  if (!allocated()) return;
  double **impulses = state.vec(impulse_field);
  double **differences = state.vec(difference_field);
  for (int k = 0; k < 3; k++) impulses[i][k] = differences[i][k] = std::nan("");
}

/* ---------------------------------------------------------------------- */

void ParasiticDamping::init(double damp_time, double dt, bool thermostats, bool forcing)
{
  damp_auto = (damp_time < 0.0);
  thermostatted = thermostats;
  rate = 0.0;
  if (damp_time > 0.0)
    rate = 1.0 / damp_time;
  else if (damp_auto)
    rate = 1.0 / (AUTO_STEPS * dt);
  on = (damp_time > 0.0) || (damp_auto && thermostats && (forcing || ever_changed));
  impulse = 0;
  for (auto &s : last) s.beta = 0.0;
  if ((damp_time > 0.0) || (damp_auto && thermostats)) allocate();
}

/* ---------------------------------------------------------------------- */

int ParasiticDamping::take_impulse()
{
  const int flag = impulse;
  impulse = 0;
  return flag;
}

/* ---------------------------------------------------------------------- */

bool ParasiticDamping::impulse_anywhere(bool seen)
{
  if (seen && thermostatted) ever_changed = true;
  const bool was = on;
  if (seen && damp_auto && thermostatted) on = true;
  return on && !was;
}

/* ---------------------------------------------------------------------- */

double ParasiticDamping::beta(double h) const
{
  return on ? std::min(1.0, rate * std::fabs(h)) : 0.0;
}

/* ---------------------------------------------------------------------- */

const ParasiticDamping::Step *ParasiticDamping::step(double h, int clock)
{
  Step &s = last[clock];
  s.beta = beta(h);
  if (s.beta == 0.0) return nullptr;
  s.h = h;
  s.impulse = state.vec(impulse_field);
  s.difference = state.vec(difference_field);
  s.history = history[clock];
  return &s;
}

/* ---------------------------------------------------------------------- */

void ParasiticDamping::forget_history()
{
  for (auto &flag : history) flag = false;
}

/* ---------------------------------------------------------------------- */

void ParasiticDamping::note(LAMMPS *lmp, const char *style, bool from_now) const
{
  if (lmp->comm->me != 0) return;
  const std::string when = from_now ? fmt::format("from step {}", lmp->update->ntimestep)
                                    : std::string("in this run");
  utils::logmesg(
      lmp, "Fix {}: damp auto damps the parasitic mode over {} steps {} (a thermostat acts)\n",
      style, AUTO_STEPS, when);
}
