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

#include "pe_jump_options.h"

#include "error.h"
#include "lammps.h"
#include "pe_jump_force_sampler.h"
#include "pe_jump_quadrature.h"
#include "utils.h"

#include <cstring>
#include <string>

using namespace LAMMPS_NS;
using namespace LAMMPS_NS::PEJump;

/* ---------------------------------------------------------------------- */

Options::Options() :
    family(Quadrature::LEGENDRE), npoints(1), init_style(KICK), sample_mask(ForceSampler::ALL),
    auto_tol(0.0), adapt_eps(0.0), adapt_dtmin(0.0), adapt_dtmax(0.0), compensate(-1),
    damp_time(-1.0), buffer_layers(0), buffer_reach(0.0), fast_auto(0.0)
{
}

/* ---------------------------------------------------------------------- */

void Options::parse(LAMMPS *lmp, const char *style, int narg, char **arg, int first,
                    bool two_clocks)
{
  const std::string fix = std::string("fix ") + style;
  int iarg = first;
  while (iarg < narg) {
    if (strcmp(arg[iarg], "quadrature") == 0) {
      iarg = quadrature(lmp, style, narg, arg, iarg);
    } else if (strcmp(arg[iarg], "init") == 0) {
      if (iarg + 2 > narg) utils::missing_cmd_args(FLERR, fix + " init", lmp->error);
      if (strcmp(arg[iarg + 1], "kick") == 0)
        init_style = Options::KICK;
      else if (strcmp(arg[iarg + 1], "paper") == 0)
        init_style = Options::PAPER;
      else
        lmp->error->all(FLERR, "Unknown fix {} init style: {}", style, arg[iarg + 1]);
      iarg += 2;
    } else if (strcmp(arg[iarg], "adapt") == 0) {
      if (iarg + 4 > narg) utils::missing_cmd_args(FLERR, fix + " adapt", lmp->error);
      adapt_eps = utils::numeric(FLERR, arg[iarg + 1], false, lmp);
      adapt_dtmin = utils::numeric(FLERR, arg[iarg + 2], false, lmp);
      adapt_dtmax = utils::numeric(FLERR, arg[iarg + 3], false, lmp);
      if (adapt_eps <= 0.0) lmp->error->all(FLERR, "Fix {} adapt eps must be > 0", style);
      if ((adapt_dtmin <= 0.0) || (adapt_dtmax < adapt_dtmin))
        lmp->error->all(FLERR, "Fix {} adapt needs 0 < dtmin <= dtmax", style);
      iarg += 4;
    } else if ((strcmp(arg[iarg], "buffer") == 0) || (strcmp(arg[iarg], "fast") == 0)) {
      if (!two_clocks)
        lmp->error->all(FLERR,
                        "Fix {} has a single clock: the {} keyword belongs to fix pe_jump/async",
                        style, arg[iarg]);
      iarg = clock_keyword(lmp, style, narg, arg, iarg);
    } else if (strcmp(arg[iarg], "damp") == 0) {
      if (iarg + 2 > narg) utils::missing_cmd_args(FLERR, fix + " damp", lmp->error);
      if (strcmp(arg[iarg + 1], "auto") == 0) {
        damp_time = -1.0;
      } else {
        damp_time = utils::numeric(FLERR, arg[iarg + 1], false, lmp);
        if (!(damp_time >= 0.0))
          lmp->error->all(FLERR, "Fix {} damp needs a time >= 0 or auto", style);
      }
      iarg += 2;
    } else if (strcmp(arg[iarg], "compensate") == 0) {
      if (iarg + 2 > narg) utils::missing_cmd_args(FLERR, fix + " compensate", lmp->error);
      compensate = utils::logical(FLERR, arg[iarg + 1], false, lmp);
      iarg += 2;
    } else if (strcmp(arg[iarg], "sample") == 0) {
      iarg = sample(lmp, style, narg, arg, iarg);
    } else {
      lmp->error->all(FLERR, "Unknown fix {} keyword: {}", style, arg[iarg]);
    }
  }
}

/* ----------------------------------------------------------------------
   the quadrature keyword at arg[iarg]: returns the index after it
------------------------------------------------------------------------- */

int Options::quadrature(LAMMPS *lmp, const char *style, int narg, char **arg, int iarg)
{
  const std::string fix = std::string("fix ") + style;
  if (iarg + 2 > narg) utils::missing_cmd_args(FLERR, fix + " quadrature", lmp->error);
  const std::string which = arg[iarg + 1];
  Quadrature::Family named;
  auto_tol = 0.0;    // the last quadrature keyword wins
  if (which == "midpoint") {
    family = Quadrature::LEGENDRE;
    npoints = 1;
    iarg += 2;
  } else if (which == "auto") {
    if (iarg + 3 > narg) utils::missing_cmd_args(FLERR, fix + " quadrature auto", lmp->error);
    auto_tol = utils::numeric(FLERR, arg[iarg + 2], false, lmp);
    if (auto_tol <= 0.0) lmp->error->all(FLERR, "Fix {} quadrature auto needs TOL > 0", style);
    family = Quadrature::LOBATTO;
    npoints = 5;
    iarg += 3;
  } else if (Quadrature::family_named(which, named)) {
    if (iarg + 3 > narg) utils::missing_cmd_args(FLERR, fix + " quadrature " + which, lmp->error);
    npoints = utils::inumeric(FLERR, arg[iarg + 2], false, lmp);
    family = named;
    const int nmin = Quadrature::min_points(named);
    if ((npoints < nmin) || (npoints > Quadrature::MAX_POINTS))
      lmp->error->all(FLERR, "Fix {} quadrature {} needs {} to {} points, got {}", style, which,
                      nmin, Quadrature::MAX_POINTS, npoints);
    iarg += 3;
  } else {
    lmp->error->all(FLERR, "Unknown fix {} quadrature rule: {}", style, which);
  }
  return iarg;
}

/* ----------------------------------------------------------------------
   the sample keyword at arg[iarg]: returns the index after its names
------------------------------------------------------------------------- */

int Options::sample(LAMMPS *lmp, const char *style, int narg, char **arg, int iarg)
{
  sample_mask = 0;
  ++iarg;
  while (iarg < narg) {
    const int bit = ForceSampler::parse(arg[iarg]);
    if (!bit) break;
    sample_mask |= bit;
    ++iarg;
  }
  if (!sample_mask)
    lmp->error->all(FLERR,
                    "Fix {} sample needs one or more of pair, bond, angle, dihedral, improper, "
                    "kspace, or all",
                    style);
  return iarg;
}

/* ----------------------------------------------------------------------
   the keywords of the clocks of pe_jump/async (buffer, fast) at arg[iarg]:
   returns the index after them
------------------------------------------------------------------------- */

int Options::clock_keyword(LAMMPS *lmp, const char *style, int narg, char **arg, int iarg)
{
  const std::string fix = std::string("fix ") + style;
  if (strcmp(arg[iarg], "buffer") == 0) {
    if (iarg + 2 > narg) utils::missing_cmd_args(FLERR, fix + " buffer", lmp->error);
    buffer_layers = utils::inumeric(FLERR, arg[iarg + 1], false, lmp);
    if (buffer_layers < 0) lmp->error->all(FLERR, "Fix {} buffer needs N >= 0", style);
    if ((iarg + 2 >= narg) || (strcmp(arg[iarg + 2], "within") != 0)) return iarg + 2;
    if (iarg + 4 > narg) utils::missing_cmd_args(FLERR, fix + " buffer N within", lmp->error);
    buffer_reach = utils::numeric(FLERR, arg[iarg + 3], false, lmp);
    if (!(buffer_reach > 0.0))
      lmp->error->all(FLERR, "Fix {} buffer N within D needs D > 0 (a distance), got {}", style,
                      arg[iarg + 3]);
    return iarg + 4;
  }
  if (iarg + 3 > narg) utils::missing_cmd_args(FLERR, fix + " fast", lmp->error);
  if (strcmp(arg[iarg + 1], "auto") != 0)
    lmp->error->all(FLERR, "Fix {} fast takes auto TOL, got {}", style, arg[iarg + 1]);
  fast_auto = utils::numeric(FLERR, arg[iarg + 2], false, lmp);
  if (!(fast_auto > 0.0) || (fast_auto > 0.5))
    lmp->error->all(
        FLERR, "Fix {} fast auto needs 0 < TOL <= 0.5 (a fraction of the neighbor skin), got {}",
        style, arg[iarg + 2]);
  return iarg + 3;
}
