// the plugin (pejumpplugin.so) brings fix pe_jump and fix pe_jump/async into
// a LAMMPS that does not have them, and integrates exactly like the
// built-in styles

#include "pe_jump_systems.h"

#include "exceptions.h"
#include "plugin.h"

#include "gmock/gmock.h"
#include "gtest/gtest.h"

#include <cmath>
#include <iterator>

using namespace PEJumpTest;
using ::testing::HasSubstr;

namespace {

const char *fixes[] = {"fix 1 chain pe_jump quadrature lobatto 3",
                       "fix 1 chain pe_jump/async 10 fast quadrature lobatto 3"};

void chain(Sim &s)
{
  slow_fast_chain(s, 3, 10.0, {0.1, -0.05, 0.02, 0.3, -0.2, 0.1}, {0.5, 0.0, 0.0, 0.0, 1.0, 0.0});
}

// positions and velocities of the chain at t = 4: 2000 steps of 0.002 (fix
// pe_jump/async 10: 200 coarse steps of 0.02)
std::vector<double> run(Sim &s, const std::string &fix)
{
  const bool async = fix.find("pe_jump/async 10 ") != std::string::npos;
  s.cmds({fix, async ? "timestep 0.02" : "timestep 0.002", "thermo 0",
          async ? "run 200 post no" : "run 2000 post no"});
  std::vector<double> out;
  for (int id = 2; id <= 7; ++id) {
    out.push_back(s.x(id, 0));
    out.push_back(s.v(id, 0));
  }
  return out;
}

}    // namespace

// true if the fix pe_jump of this instance is the plugin's: LAMMPS from
// 4 Jul 2026 keeps a loaded plugin for the whole process and registers it
// again in every new instance, LAMMPS 4 Feb 2025 does not
bool plugin_in_use(Sim &s)
{
  const int index = LAMMPS_NS::plugin_find("fix", "pe_jump");
  if (index < 0) return false;
  const auto *fix_map = s.lmp->modify->fix_map;
  const auto entry = fix_map->find("pe_jump");
  return (entry != fix_map->end()) &&
      (reinterpret_cast<void *>(entry->second) ==
       reinterpret_cast<void *>(LAMMPS_NS::plugin_get_info(index)->creator.v2));
}

TEST(PEJumpPlugin, SameTrajectoryAsBuiltInStyles)
{
  // every built-in run comes before the first plugin load of the process
  std::vector<std::vector<double>> builtin;
  for (const std::string fix : fixes) {
    Sim s;
    chain(s);
    ASSERT_FALSE(plugin_in_use(s));
    builtin.push_back(run(s, fix));
  }
  for (size_t n = 0; n < std::size(fixes); ++n) {
    const std::string fix = fixes[n];
    std::vector<double> plugin;
    {
      Sim s;
      chain(s);
      if (!plugin_in_use(s)) {
        // make this instance one without the styles, as a stock lmp would be
        auto *fix_map = s.lmp->modify->fix_map;
        ASSERT_EQ(fix_map->erase("pe_jump"), 1u);
        ASSERT_EQ(fix_map->erase("pe_jump/async"), 1u);
        const std::string error = error_in(s, fix);
        if (error == "no error") FAIL() << "the fix exists without the plugin";
        EXPECT_THAT(error, HasSubstr("Unrecognized fix style"));
        s.cmd(std::string("plugin load ") + PEJUMP_PLUGIN_PATH);
      }
      ASSERT_TRUE(plugin_in_use(s));
      plugin = run(s, fix);
    }
    ASSERT_EQ(builtin[n].size(), plugin.size());
    // the same sources with the same compiler flags: identical numbers
    for (size_t i = 0; i < plugin.size(); ++i)
      EXPECT_EQ(builtin[n][i], plugin[i]) << fix << " " << i;
    // and the run did move the chain
    EXPECT_GT(std::fabs(builtin[n][0] - 1.6), 1e-3);
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
  const std::string error = error_in(s, std::string("plugin load ") + PEJUMP_OTHER_PLUGIN_PATH);
  if (error == "no error") FAIL() << "a plugin for another LAMMPS version was loaded";
  EXPECT_THAT(error,
              HasSubstr("built for LAMMPS version 1 Jan 2000 (20000101) but this "
                        "LAMMPS is version " +
                        std::to_string(s.lmp->num_ver)));
  EXPECT_EQ(fix_map->count("pe_jump"), 0u);
}
