// The project's bad-input suite: every case of bad_inputs.txt runs in a
// fresh LAMMPS instance and must end exactly as the file says, with a
// specific ERROR, a message in the log, or a clean run whose energies are
// finite. The same binary runs on 1, 2 and 4 MPI ranks (ctest), so that
// every error is raised on all ranks and no case hangs.
//
// Format of a case (one line): category | system | commands | outcome
//   system: none, lj, chain, gas, charged, sphere (set-ups below)
//   commands: LAMMPS commands separated by " ; "; pseudo commands:
//     !truncate FILE BYTES   cut a file to its first BYTES bytes
//     !corrupt FILE OFFSET   flip the bits of the byte at OFFSET
//   outcome: ok, error: REGEX, log: REGEX

#include "pe_jump_systems.h"

#include "exceptions.h"
#include "utils.h"

#include "gmock/gmock.h"
#include "gtest/gtest.h"

#include <cmath>
#include <cstdio>
#include <filesystem>
#include <fstream>
#include <regex>
#include <string>
#include <vector>

using namespace PEJumpTest;

namespace {

struct Case {
  int line;
  std::string category, system, outcome;
  std::vector<std::string> commands;
};

std::string trim(const std::string &s)
{
  const auto first = s.find_first_not_of(" \t");
  if (first == std::string::npos) return "";
  return s.substr(first, s.find_last_not_of(" \t") - first + 1);
}

std::vector<std::string> split(const std::string &s, const std::string &sep)
{
  std::vector<std::string> parts;
  size_t start = 0, pos;
  while ((pos = s.find(sep, start)) != std::string::npos) {
    parts.push_back(trim(s.substr(start, pos - start)));
    start = pos + sep.size();
  }
  parts.push_back(trim(s.substr(start)));
  return parts;
}

std::vector<Case> read_cases()
{
  std::ifstream in(PEJUMP_BAD_INPUTS);
  std::vector<Case> cases;
  std::string text;
  int line = 0;
  while (std::getline(in, text)) {
    ++line;
    if (trim(text).empty() || (trim(text)[0] == '#')) continue;
    const auto fields = split(text, " | ");
    if (fields.size() != 4) {
      ADD_FAILURE() << "bad_inputs.txt line " << line << " has " << fields.size() << " fields";
      continue;
    }
    cases.push_back({line, fields[0], fields[1], fields[3], split(fields[2], " ; ")});
  }
  return cases;
}

void set_up(Sim &s, const std::string &system)
{
  if (system == "none") return;
  if (system == "lj") {
    lj_liquid(s, 3);
    s.cmds({"region slab block 0 1 INF INF INF INF", "group fast region slab", "thermo 0",
            "timestep 0.005"});
  } else if (system == "chain") {
    double q[6], p[6];
    fpu_gni_values(50.0, q, p);
    fpu_chain(s, 50.0, q, p);
    s.cmds({"group fast id 2:4", "thermo 0", "timestep 0.001"});
  } else if (system == "gas") {
    s.cmds({"units lj", "atom_style atomic", "atom_modify map array", "boundary p p p",
            "region box block 0 20 0 20 0 20", "create_box 1 box",
            "create_atoms 1 random 50 4711 NULL", "mass 1 1.0", "velocity all create 1.0 5511",
            "pair_style zero 1.0", "pair_coeff * *", "group fast id 1:10", "thermo 0",
            "timestep 0.005"});
  } else if (system == "charged") {
    s.cmds({"units lj", "atom_style charge", "atom_modify map array", "lattice fcc 0.8442",
            "region box block 0 3 0 3 0 3", "create_box 1 box", "create_atoms 1 box", "mass 1 1.0",
            "set type 1 charge 0.0", "velocity all create 1.0 4928",
            "pair_style lj/cut/coul/long 2.5", "pair_coeff 1 1 1.0 1.0", "kspace_style ewald 1e-4",
            "kspace_modify gewald 0.9", "region slab block 0 1 INF INF INF INF",
            "group fast region slab", "thermo 0", "timestep 0.005"});
  } else if (system == "sphere") {
    s.cmds({"units lj", "atom_style sphere", "region box block 0 10 0 10 0 10", "create_box 1 box",
            "create_atoms 1 random 20 4711 NULL", "pair_style zero 1.0", "pair_coeff * *",
            "group fast id 1:5", "thermo 0", "timestep 0.005"});
  } else {
    throw std::runtime_error("unknown system " + system);
  }
}

void pseudo_command(const std::string &command)
{
  const auto words = LAMMPS_NS::utils::split_words(command);
  if (words.size() != 3) throw std::runtime_error("bad pseudo command " + command);
  const long value = std::stol(words[2]);
  if (words[0] == "!truncate") {
    std::filesystem::resize_file(words[1], value);
  } else if (words[0] == "!corrupt") {
    std::fstream f(words[1], std::ios::in | std::ios::out | std::ios::binary);
    f.seekg(value);
    char c = 0;
    f.get(c);
    f.seekp(value);
    f.put(static_cast<char>(~c));
  } else {
    throw std::runtime_error("unknown pseudo command " + command);
  }
}

// runs one case; returns "" if it ends as expected, else what went wrong
std::string run_case(const Case &c)
{
  int me = 0;
  MPI_Comm_rank(MPI_COMM_WORLD, &me);
  const bool want_log = LAMMPS_NS::utils::strmatch(c.outcome, "^log:");
  Sim s(MPI_COMM_WORLD, !want_log);
  std::string error;
  if (want_log) ::testing::internal::CaptureStdout();
  // the suite runs on 1, 2 and 4 ranks at the same time in one folder:
  // each run has its own file names
  int nprocs = 1;
  MPI_Comm_size(MPI_COMM_WORLD, &nprocs);
  const std::string tag = "pe_jump_bad_np" + std::to_string(nprocs) + ".";
  const std::string caught = error_from([&] {
    set_up(s, c.system);
    for (auto command : c.commands) {
      for (size_t at; (at = command.find("pe_jump_bad.")) != std::string::npos;)
        command.replace(at, 12, tag);
      if (command[0] == '!') {
        MPI_Barrier(MPI_COMM_WORLD);
        if (me == 0) pseudo_command(command);
        MPI_Barrier(MPI_COMM_WORLD);
      } else {
        s.cmd(command);
      }
    }
  });
  if (caught != "no error") error = caught;
  const std::string out = want_log ? ::testing::internal::GetCapturedStdout() : "";

  if (LAMMPS_NS::utils::strmatch(c.outcome, "^error:")) {
    const std::string pattern = trim(c.outcome.substr(6));
    if (error.empty()) return "no error, expected " + pattern;
    if (!std::regex_search(error, std::regex(pattern)))
      return "error \"" + error + "\" does not match " + pattern;
    return "";
  }
  if (!error.empty()) return "unexpected error: " + error;
  if (want_log) {
    const std::string pattern = trim(c.outcome.substr(4));
    if ((me == 0) && !std::regex_search(out, std::regex(pattern)))
      return "the log lacks " + pattern;
  } else if (c.outcome != "ok") {
    return "unknown outcome " + c.outcome;
  }
  if (s.lmp->atom->natoms > 0 && s.lmp->update->first_update) {
    const double pe = s.eval("pe"), ke = s.eval("ke");
    if (!std::isfinite(pe) || !std::isfinite(ke)) return "non-finite energies";
  }
  return "";
}

}    // namespace

TEST(PEJumpBadInputs, EveryCaseEndsAsExpected)
{
  const auto cases = read_cases();
  ASSERT_GE(cases.size(), 100u);
  int me = 0;
  MPI_Comm_rank(MPI_COMM_WORLD, &me);
  for (const auto &c : cases) {
    const std::string problem = run_case(c);
    EXPECT_EQ(problem, "") << "bad_inputs.txt line " << c.line << " (" << c.category
                           << "): " << LAMMPS_NS::utils::join_words(c.commands, " ; ");
    MPI_Barrier(MPI_COMM_WORLD);
    if (me == 0) {
      int nprocs = 1;
      MPI_Comm_size(MPI_COMM_WORLD, &nprocs);
      const std::string tag = "pe_jump_bad_np" + std::to_string(nprocs) + ".";
      std::remove((tag + "restart").c_str());
      std::remove((tag + "data").c_str());
    }
  }
  if (me == 0) std::printf("%zu bad-input cases\n", cases.size());
}
