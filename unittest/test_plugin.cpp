// the plugin (pejumpplugin.so) brings fix pe_jump and fix pe_jump/async into
// a LAMMPS that does not have them, and integrates exactly like the
// built-in styles

#include "pe_jump_systems.h"

#include "exceptions.h"

#include "gmock/gmock.h"
#include "gtest/gtest.h"

#include <cmath>

using namespace PEJumpTest;
using ::testing::HasSubstr;

namespace {

const char *fixes[] = {"fix 1 chain pe_jump quadrature lobatto 3",
                       "fix 1 chain pe_jump/async 10 fast quadrature lobatto 3"};

void chain(Sim &s)
{
  slow_fast_chain(s, 3, 10.0, {0.1, -0.05, 0.02, 0.3, -0.2, 0.1}, {0.5, 0.0, 0.0, 0.0, 1.0, 0.0});
}

// positions and velocities of the chain after 2000 steps
std::vector<double> run(Sim &s, const std::string &fix)
{
  s.cmds({fix, "timestep 0.002", "thermo 0", "run 2000 post no"});
  std::vector<double> out;
  for (int id = 2; id <= 7; ++id) {
    out.push_back(s.x(id, 0));
    out.push_back(s.v(id, 0));
  }
  return out;
}

}    // namespace

TEST(PEJumpPlugin, SameTrajectoryAsBuiltInStyles)
{
  for (const std::string fix : fixes) {
    std::vector<double> builtin, plugin;
    {
      Sim s;
      chain(s);
      builtin = run(s, fix);
    }
    {
      Sim s;
      chain(s);
      // make this instance one without the styles, as a stock lmp would be
      auto *fix_map = s.lmp->modify->fix_map;
      ASSERT_EQ(fix_map->erase("pe_jump"), 1u);
      ASSERT_EQ(fix_map->erase("pe_jump/async"), 1u);
      try {
        s.cmd(fix);
        FAIL() << "the fix exists without the plugin";
      } catch (LAMMPS_NS::LAMMPSException &e) {
        EXPECT_THAT(e.what(), HasSubstr("Unrecognized fix style"));
      }
      s.cmd(std::string("plugin load ") + PEJUMP_PLUGIN_PATH);
      ASSERT_EQ(fix_map->count("pe_jump"), 1u);
      ASSERT_EQ(fix_map->count("pe_jump/async"), 1u);
      plugin = run(s, fix);
    }
    ASSERT_EQ(builtin.size(), plugin.size());
    // the same sources with the same compiler flags: identical numbers
    for (size_t i = 0; i < builtin.size(); ++i) EXPECT_EQ(builtin[i], plugin[i]) << fix << " " << i;
    // and the run did move the chain
    EXPECT_GT(std::fabs(builtin[0] - 1.6), 1e-3);
  }
}

// a plugin built for another LAMMPS version refuses to load, naming both
// versions, and registers nothing
TEST(PEJumpPlugin, RefusesAnotherLammpsVersion)
{
  Sim s;
  auto *fix_map = s.lmp->modify->fix_map;
  fix_map->erase("pe_jump");
  fix_map->erase("pe_jump/async");
  try {
    s.cmd(std::string("plugin load ") + PEJUMP_OTHER_PLUGIN_PATH);
    FAIL() << "a plugin for another LAMMPS version was loaded";
  } catch (LAMMPS_NS::LAMMPSException &e) {
    EXPECT_THAT(e.what(),
                HasSubstr("built for LAMMPS version 4 Jul 2026 (20260704) but this "
                          "LAMMPS is version " +
                          std::to_string(s.lmp->num_ver)));
  }
  EXPECT_EQ(fix_map->count("pe_jump"), 0u);
}
