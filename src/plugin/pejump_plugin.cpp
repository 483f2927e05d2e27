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

#include "exceptions.h"
#include "lammpsplugin.h"
#include "library.h"
#include "version.h"

#include <cstdio>
#include <cstring>
#include <string>

#include "fix_pe_jump.h"
#include "fix_pe_jump_async.h"
#include "pe_jump_errors.h"

using namespace LAMMPS_NS;

static Fix *pe_jump_creator(LAMMPS *lmp, int argc, char **argv)
{
  return new FixPEJump(lmp, argc, argv);
}

static Fix *pe_jump_async_creator(LAMMPS *lmp, int argc, char **argv)
{
  return new FixPEJumpAsync(lmp, argc, argv);
}

// the LAMMPS version the plugin was compiled against (a test builds a
// plugin that claims another one)
#ifndef PEJUMP_PLUGIN_BUILT_FOR
#define PEJUMP_PLUGIN_BUILT_FOR LAMMPS_VERSION
#endif

// "4 Feb 2025" -> 20250204 (0 if not a date), as LAMMPS numbers versions
static int version_number(const char *date)
{
  static const char *months[] = {"Jan", "Feb", "Mar", "Apr", "May", "Jun",
                                 "Jul", "Aug", "Sep", "Oct", "Nov", "Dec"};
  int day = 0, year = 0;
  char month[4] = {0};
  if (sscanf(date, "%d %3s %d", &day, month, &year) != 3) return 0;
  for (int m = 0; m < 12; m++)
    if (strcmp(month, months[m]) == 0) return 10000 * year + 100 * (m + 1) + day;
  return 0;
}

extern "C" void lammpsplugin_init(void *lmp, void *handle, void *regfunc)
{
  // the styles are compiled against the class layout of one LAMMPS version:
  // in another one they could run on corrupted memory. The running
  // version comes through the C library interface, which does not depend
  // on that layout
  const int built_for = version_number(PEJUMP_PLUGIN_BUILT_FOR);
  const int running = lammps_version(lmp);
  if (built_for != running) {
    const std::string message = std::string("The PE-JUMP plugin was built for LAMMPS version ") +
        PEJUMP_PLUGIN_BUILT_FOR + " (" + std::to_string(built_for) +
        ") but this LAMMPS is version " + std::to_string(running) + PEJump::errorurl(65);
    // printed here (lammps_error() would end the process of a library
    // caller), then the plugin load stops with the error
    if (lammps_extract_setting(lmp, "world_rank") == 0) {
      fprintf(stderr, "ERROR: %s\n", message.c_str());
      fflush(stderr);
    }
    throw LAMMPS_NS::LAMMPSException("ERROR: " + message + "\n");
  }

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
