// small LAMMPS systems shared by the PE-JUMP tests, driven through the C++ API

#ifndef PE_JUMP_SYSTEMS_H
#define PE_JUMP_SYSTEMS_H

#include "atom.h"
#include "domain.h"
#include "exceptions.h"
#include "fix.h"
#include "input.h"
#include "lammps.h"
#include "modify.h"
#include "update.h"
#include "variable.h"

#include <algorithm>
#include <cmath>
#include <mpi.h>
#include <string>
#include <vector>

namespace PEJumpTest {

using LAMMPS_NS::LAMMPS;

// one LAMMPS instance with output silenced
class Sim {
 public:
  explicit Sim(MPI_Comm comm = MPI_COMM_WORLD, bool quiet = true)
  {
    LAMMPS::argv args = {"pejump_test", "-log", "none", "-echo", "none", "-nocite"};
    if (quiet) {
      args.push_back("-screen");
      args.push_back("none");
    }
    lmp = new LAMMPS(args, comm);
  }
  ~Sim() { delete lmp; }
  Sim(const Sim &) = delete;
  Sim &operator=(const Sim &) = delete;

  void cmd(const std::string &line) { lmp->input->one(line); }
  void cmds(const std::vector<std::string> &lines)
  {
    for (const auto &line : lines) cmd(line);
  }
  double vec(const std::string &fix, int i)
  {
    return lmp->modify->get_fix_by_id(fix)->compute_vector(i);
  }
  double eval(const std::string &expr) { return lmp->input->variable->compute_equal(expr); }

  // position component k of the atom with tag id (serial runs)
  double x(int id, int k) { return lmp->atom->x[lmp->atom->map(id)][k]; }
  double v(int id, int k) { return lmp->atom->v[lmp->atom->map(id)][k]; }

  LAMMPS *lmp;
};

// the message of the LAMMPS error that body() raises, or "no error"
template <typename Body> std::string error_from(Body &&body)
{
  try {
    body();
  } catch (LAMMPS_NS::LAMMPSException &e) {
    return e.what();
  }
  return "no error";
}

// the first error of a sequence of commands in a fresh instance, or
// "no error"
inline std::string error_of(const std::vector<std::string> &commands)
{
  Sim s;
  return error_from([&] {
    s.cmds(commands);
  });
}
// the error of one more command in an instance, or "no error"
inline std::string error_in(Sim &s, const std::string &command)
{
  return error_from([&] {
    s.cmd(command);
  });
}
inline std::string error_of(std::vector<std::string> setup, const std::string &failing)
{
  setup.push_back(failing);
  return error_of(setup);
}

// positions of all atoms, by atom ID (serial runs)
inline std::vector<double> positions(Sim &s)
{
  std::vector<double> x;
  for (int id = 1; id <= s.lmp->atom->natoms; id++)
    for (int k = 0; k < 3; k++) x.push_back(s.x(id, k));
  return x;
}

// unwrapped positions of all atoms, by atom ID (serial runs)
inline std::vector<double> unwrapped_positions(Sim &s)
{
  std::vector<double> x;
  for (int id = 1; id <= s.lmp->atom->natoms; id++) {
    double unwrap[3];
    const int i = s.lmp->atom->map(id);
    s.lmp->domain->unmap(s.lmp->atom->x[i], s.lmp->atom->image[i], unwrap);
    x.insert(x.end(), unwrap, unwrap + 3);
  }
  return x;
}

// largest difference of two equally long lists of values
inline double max_diff(const std::vector<double> &a, const std::vector<double> &b)
{
  double d = 0.0;
  for (size_t i = 0; i < a.size(); ++i) d = std::max(d, std::fabs(a[i] - b[i]));
  return d;
}

// the paper's Fermi-Pasta-Ulam chain (m = 3): 6 moving particles of mass 1
// between two fixed walls, soft quartic springs (q_{2i+1}-q_{2i})^4 and stiff
// springs (omega^2/4)(q_{2i}-q_{2i-1})^2, realised along x with spacing A:
// atom i+1 sits at x = i*A + q_i, i = 0..7, atoms 1 and 8 are the walls;
// coordinates stay below 11, so round-off of the energies is ~1e-15
constexpr double FPU_SPACING = 1.5;

inline void fpu_chain(Sim &s, double omega, const double q[6], const double p[6],
                      const std::string &units = "lj")
{
  s.cmds({"units " + units, "atom_style bond", "atom_modify map array", "boundary f f f",
          "region box block -2 13 -5 5 -5 5", "create_box 1 box bond/types 2 extra/bond/per/atom 2",
          "mass 1 1.0"});
  for (int i = 0; i < 8; ++i)
    s.cmd("create_atoms 1 single " + std::to_string(i * FPU_SPACING) + " 0 0");
  // exact positions and velocities through the API (no text round trip)
  for (int i = 0; i < 8; ++i) {
    const int j = s.lmp->atom->map(i + 1);
    if (j < 0) continue;    // owned by another rank
    s.lmp->atom->x[j][0] = i * FPU_SPACING + ((i == 0 || i == 7) ? 0.0 : q[i - 1]);
    s.lmp->atom->v[j][0] = (i == 0 || i == 7) ? 0.0 : p[i - 1];
  }
  s.cmds({"bond_style hybrid harmonic class2",
          "bond_coeff 1 harmonic " + std::to_string(0.25 * omega * omega) + " 1.5",
          "bond_coeff 2 class2 1.5 0.0 0.0 1.0"});
  for (int i = 1; i <= 7; ++i)
    s.cmd("create_bonds single/bond " + std::string(i % 2 ? "2 " : "1 ") + std::to_string(i) + " " +
          std::to_string(i + 1));
  s.cmds({"pair_style zero 1.0", "pair_coeff * *", "comm_modify cutoff 4.0", "group walls id 1 8",
          "group chain id 2:7"});
}

// the paper's slow/fast chain (section 4.3.1): walls q_0 and q_{2m+1}, m
// stiff springs (omega^2/4)(q_i - q_{i-1})^2 (i = 1..m) and m+1 soft
// springs (q_{i+1} - q_i)^4 (i = m..2m), all as bond_style class2 so that
// fix pe_jump/async can split them; groups fast (q_1..q_m) and walls.
// Atom i+1 sits at x = i*A + q_i, A = FPU_SPACING.
inline void slow_fast_chain(Sim &s, int m, double omega2, const std::vector<double> &q,
                            const std::vector<double> &p)
{
  const int n = 2 * m + 2;
  s.cmds({"units lj", "atom_style bond", "atom_modify map array", "boundary f f f",
          "region box block -2 " + std::to_string((n + 1) * 1.5) + " -5 5 -5 5",
          "create_box 1 box bond/types 2 extra/bond/per/atom 2", "mass 1 1.0"});
  for (int i = 0; i < n; ++i) s.cmd("create_atoms 1 single " + std::to_string(i * 1.5) + " 0 0");
  for (int i = 0; i < n; ++i) {
    const int j = s.lmp->atom->map(i + 1);
    if (j < 0) continue;    // owned by another rank
    const bool wall = (i == 0) || (i == n - 1);
    s.lmp->atom->x[j][0] = i * 1.5 + (wall ? 0.0 : q[i - 1]);
    s.lmp->atom->v[j][0] = wall ? 0.0 : p[i - 1];
  }
  s.cmds({"bond_style class2", "bond_coeff 1 1.5 " + std::to_string(0.25 * omega2) + " 0.0 0.0",
          "bond_coeff 2 1.5 0.0 0.0 1.0"});
  for (int i = 1; i < n; ++i)
    s.cmd("create_bonds single/bond " + std::string(i <= m ? "1 " : "2 ") + std::to_string(i) +
          " " + std::to_string(i + 1));
  s.cmds({"pair_style zero 1.0", "pair_coeff * *", "comm_modify cutoff 4.0",
          "group walls id 1 " + std::to_string(n), "group fast id 2:" + std::to_string(m + 1),
          "group chain id 2:" + std::to_string(n - 1)});
}

// GNI book initial values: x_1 = 1, y_1 = 1, x_4 = 1/omega, y_4 = 1
inline void fpu_gni_values(double omega, double q[6], double p[6])
{
  const double s2 = std::sqrt(2.0);
  const double x[6] = {1.0, 0.0, 0.0, 1.0 / omega, 0.0, 0.0};
  const double y[6] = {1.0, 0.0, 0.0, 1.0, 0.0, 0.0};
  for (int i = 0; i < 3; ++i) {
    q[2 * i] = (x[i] - x[3 + i]) / s2;
    q[2 * i + 1] = (x[i] + x[3 + i]) / s2;
    p[2 * i] = (y[i] - y[3 + i]) / s2;
    p[2 * i + 1] = (y[i] + y[3 + i]) / s2;
  }
}

// periodic 1D chain of n particles along x, spacing 1, harmonic springs
// E = K (r - 1)^2, positions displaced and velocities set from a seed
inline void harmonic_ring(Sim &s, int n, double K, double amplitude, int seed)
{
  const std::string len = std::to_string(n);
  s.cmds({"units lj", "atom_style bond", "atom_modify map array", "boundary p p p",
          "region box block 0 " + len + " -5 5 -5 5",
          "create_box 1 box bond/types 1 extra/bond/per/atom 2", "mass 1 1.0"});
  for (int i = 0; i < n; ++i) s.cmd("create_atoms 1 single " + std::to_string(i + 0.5) + " 0 0");
  unsigned state = seed;
  auto uniform = [&state]() {
    state = 1664525u * state + 1013904223u;
    return (state >> 8) / double(1u << 24) - 0.5;
  };
  for (int i = 0; i < n; ++i) {
    const double dx = 0.1 * amplitude * uniform(), v = amplitude * uniform();
    const int j = s.lmp->atom->map(i + 1);
    if (j < 0) continue;    // owned by another rank
    s.lmp->atom->x[j][0] += dx;
    s.lmp->atom->v[j][0] = v;
  }
  s.cmds({"bond_style harmonic", "bond_coeff 1 " + std::to_string(K) + " 1.0"});
  for (int i = 1; i <= n; ++i)
    s.cmd("create_bonds single/bond 1 " + std::to_string(i) + " " + std::to_string(i % n + 1));
  s.cmds({"pair_style zero 1.0", "pair_coeff * *"});
}

// small LJ liquid (256 atoms), periodic
inline void lj_liquid(Sim &s, int cells = 4, const std::string &extra_velocity = "")
{
  const std::string c = std::to_string(cells);
  s.cmds({"units lj", "atom_style atomic", "atom_modify map array", "lattice fcc 0.8442",
          "region box block 0 " + c + " 0 " + c + " 0 " + c, "create_box 1 box",
          "create_atoms 1 box", "mass 1 1.0",
          "velocity all create 1.5 87287 loop geom " + extra_velocity, "pair_style lj/cut 2.5",
          "pair_coeff 1 1 1.0 1.0 2.5", "neighbor 0.3 bin",
          "neigh_modify every 1 delay 0 check yes"});
}

// the paper's inhomogeneous wave u_tt = (c^2 u_x)_x on (0,1), u = 0 at the
// ends, c = 10 for x <= 1/2 and 1 beyond, on n intervals of length dx = 1/n
// with unit masses: site i = atom i+1 at x = i + u_i, the spring between
// sites i-1 and i has K = c^2/(2 dx^2) (bond type 1 stiff, 2 soft). Groups:
// ends (sites 0, n), chain (the others), fast (sites 1..n/2: x_i <= 1/2).
// Initial values: the right-going pulse u0 = 1e-2 exp(-(20(x-0.2))^2),
// v0 = -c u0' on (0, 1/2)
inline void inhomogeneous_wave(Sim &s, int n)
{
  const double dx = 1.0 / n;
  s.cmds({"units lj", "atom_style bond", "atom_modify map array", "boundary f f f",
          "region box block -1 " + std::to_string(n + 1) + " -5 5 -5 5",
          "create_box 1 box bond/types 2 extra/bond/per/atom 2", "mass 1 1.0"});
  for (int i = 0; i <= n; ++i) s.cmd("create_atoms 1 single " + std::to_string(i) + " 0 0");
  for (int i = 1; i < n; ++i) {
    const double x = i * dx;
    const double g = (x < 0.5) ? 1.0e-2 * std::exp(-std::pow(20.0 * (x - 0.2), 2)) : 0.0;
    const int j = s.lmp->atom->map(i + 1);
    if (j < 0) continue;    // owned by another rank
    s.lmp->atom->x[j][0] = i + g;
    s.lmp->atom->v[j][0] = 10.0 * 800.0 * (x - 0.2) * g;
  }
  s.cmds({"bond_style harmonic", "bond_coeff 1 " + std::to_string(50.0 / (dx * dx)) + " 1.0",
          "bond_coeff 2 " + std::to_string(0.5 / (dx * dx)) + " 1.0"});
  for (int i = 1; i <= n; ++i)
    s.cmd(fmt::format("create_bonds single/bond {} {} {}", ((i - 0.5) * dx <= 0.5) ? 1 : 2, i,
                      i + 1));
  s.cmds({"pair_style zero 1.5", "pair_coeff * *", "comm_modify cutoff 3.0",
          fmt::format("group ends id 1 {}", n + 1), "group chain subtract all ends",
          fmt::format("group fast id 2:{}", n / 2 + 1)});
}

}    // namespace PEJumpTest

#endif
