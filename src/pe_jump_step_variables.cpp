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

#include "pe_jump_step_variables.h"

#include "info.h"
#include "input.h"
#include "lammps.h"
#include "variable.h"

#include <algorithm>
#include <cctype>

using namespace LAMMPS_NS;

static bool word_char(char c)
{
  return std::isalnum(static_cast<unsigned char>(c)) || (c == '_');
}

// the number of variables: Variable::get_nvar() where LAMMPS has it (an
// inline function), else the member nvar. The names and formulas come from
// Info::get_variable_info(), which all supported versions export alike, so
// that a plugin built for one version still loads into another far enough
// to refuse it with its message.
template <typename V> static auto variable_count(V *variable, int) -> decltype(variable->get_nvar())
{
  return variable->get_nvar();
}
template <typename V> static int variable_count(V *variable, long)
{
  return variable->nvar;
}

/* ----------------------------------------------------------------------
   the formula is split into words (letters, digits, _); a word that is a
   step-number keyword, a step-number function followed by '(', or v_name
   of a known variable reads the step number
------------------------------------------------------------------------- */

static bool reads_step_number(const std::string &formula, const std::vector<std::string> &known)
{
  static const std::vector<std::string> keywords = {"step", "elapsed", "elaplong"};
  static const std::vector<std::string> functions = {"ramp", "vdisplace", "swiggle", "cwiggle"};
  const auto has = [](const std::vector<std::string> &list, const std::string &word) {
    return std::find(list.begin(), list.end(), word) != list.end();
  };
  const size_t n = formula.size();
  size_t i = 0;
  while (i < n) {
    if (!word_char(formula[i])) {
      ++i;
      continue;
    }
    size_t end = i;
    while ((end < n) && word_char(formula[end])) ++end;
    const std::string word = formula.substr(i, end - i);
    size_t next = end;
    while ((next < n) && std::isspace(static_cast<unsigned char>(formula[next]))) ++next;
    const bool call = (next < n) && (formula[next] == '(');
    if (has(keywords, word) && !call) return true;
    if (call && has(functions, word)) return true;
    if ((word.rfind("v_", 0) == 0) && has(known, word.substr(2))) return true;
    i = end;
  }
  return false;
}

/* ----------------------------------------------------------------------
   the variables are scanned until no more are found (a variable may read
   one defined after it)
------------------------------------------------------------------------- */

std::vector<std::string> PEJump::step_number_variables(LAMMPS *lmp)
{
  Variable *variable = lmp->input->variable;
  Info info(lmp);
  const int count = variable_count(variable, 0);
  std::vector<std::string> names(count), formulas(count), found;
  for (int i = 0; i < count; i++) {
    if (!variable->equalstyle(i) && !variable->atomstyle(i)) continue;
    // "Variable[  i]: name,  style = equal,  def = formula value": the
    // value, last, has no blank ("(undefined)" or a number); atom-style
    // variables have no value
    const std::string text = info.get_variable_info(i);
    const size_t colon = text.find(": "), comma = text.find(',');
    const size_t def = text.find("def =");
    if ((colon == std::string::npos) || (comma == std::string::npos) || (def == std::string::npos))
      continue;
    names[i] = text.substr(colon + 2, comma - colon - 2);
    std::string formula = text.substr(def + 5);
    while (!formula.empty() && std::isspace(static_cast<unsigned char>(formula.back())))
      formula.pop_back();
    if (variable->equalstyle(i)) {
      const size_t value = formula.find_last_of(' ');
      formula.resize((value == std::string::npos) ? 0 : value);
    }
    formulas[i] = formula;
  }
  std::vector<bool> done(count, false);
  bool more = true;
  while (more) {
    more = false;
    for (int i = 0; i < count; i++)
      if (!done[i] && !formulas[i].empty() && reads_step_number(formulas[i], found)) {
        found.emplace_back(names[i]);
        done[i] = more = true;
      }
  }
  return found;
}
