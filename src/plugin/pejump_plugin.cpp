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

// plugin entry point: registers the PE-JUMP fix styles with a running LAMMPS

#include "lammpsplugin.h"
#include "version.h"

#include "fix_pe_jump.h"
#include "fix_pe_jump_async.h"

using namespace LAMMPS_NS;

static Fix *pe_jump_creator(LAMMPS *lmp, int argc, char **argv)
{
  return new FixPEJump(lmp, argc, argv);
}

static Fix *pe_jump_async_creator(LAMMPS *lmp, int argc, char **argv)
{
  return new FixPEJumpAsync(lmp, argc, argv);
}

extern "C" void lammpsplugin_init(void *lmp, void *handle, void *regfunc)
{
  lammpsplugin_t plugin;
  auto register_plugin = (lammpsplugin_regfunc) regfunc;

  plugin.version = LAMMPS_VERSION;
  plugin.style = "fix";
  plugin.name = "pe_jump";
  plugin.info = "pseudo-energy conserving integrator with momentum jumps";
  plugin.author = "PE-JUMP developers";
  plugin.creator.v2 = (lammpsplugin_factory2 *) &pe_jump_creator;
  plugin.handle = handle;
  (*register_plugin)(&plugin, lmp);

  plugin.name = "pe_jump/async";
  plugin.info = "asynchronous (slow/fast) pseudo-energy conserving integrator";
  plugin.creator.v2 = (lammpsplugin_factory2 *) &pe_jump_async_creator;
  (*register_plugin)(&plugin, lmp);
}
