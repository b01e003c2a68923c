// "Model only what a scene requires": a scene builds the energy terms it needs
// and nothing else. Checked through the simulation's own list of terms and
// through Kokkos' allocation hook (every View allocation with its label): an
// FEM-only scene allocates no MPM, contact or friction View; an MPM scene
// without contact allocates no contact or friction View (labels: mpm_*,
// contact_*, friction_*, the broad phase's bfemp_*). And bfemp allocates none
// of its own Views in the steps of an FEM scene after the first.
#include <gtest/gtest.h>

#include <Kokkos_Core.hpp>
#include <string>
#include <vector>

#include "common/mpm_fixtures.hpp"

using namespace bfemp;
using namespace bfemp::fixtures;

namespace {

std::vector<std::string>* g_labels = nullptr;

void on_allocate(const Kokkos_Profiling_SpaceHandle, const char* label, const void*, const uint64_t) {
  if (g_labels) g_labels->push_back(label);
}

// Labels of the Views allocated while `fn` runs.
template <class Fn>
std::vector<std::string> allocations(Fn&& fn) {
  std::vector<std::string> labels;
  g_labels = &labels;
  Kokkos::Tools::Experimental::set_allocate_data_callback(on_allocate);
  fn();
  Kokkos::Tools::Experimental::set_allocate_data_callback(nullptr);
  g_labels = nullptr;
  return labels;
}

std::vector<std::string> with_prefix(const std::vector<std::string>& labels, const std::vector<std::string>& prefixes) {
  std::vector<std::string> out;
  for (const auto& l : labels)
    for (const auto& p : prefixes)
      if (l.rfind(p, 0) == 0) out.push_back(l);
  return out;
}

std::string join(const std::vector<std::string>& v) {
  std::string s;
  for (const auto& x : v) s += (s.empty() ? "" : ", ") + x;
  return s;
}

SimulationSetup<2> fem_scene() {
  auto s = block_setup<2>(0.25, 1e5, 0.3, 1000.0, 0.5);
  s.gravity = {0.0, -9.81, 0.0};
  prescribe<2>(s, "bottom");
  s.dt = 1e-2;
  return s;
}

}  // namespace

TEST(BuiltTerms, FemSceneBuildsNoMpmContactOrFriction) {
  std::unique_ptr<Simulation<2>> sim;
  const auto labels = allocations([&] {
    sim = std::make_unique<Simulation<2>>(fem_scene(), comm());
    for (int k = 0; k < 3; ++k) sim->step();
  });
  EXPECT_EQ(sim->mpm(), nullptr);
  EXPECT_EQ(sim->contact(), nullptr);
  EXPECT_EQ(sim->term_names(), std::vector<std::string>{"fem elasticity"});
  const auto foreign = with_prefix(labels, {"mpm_", "contact_", "friction_", "bfemp_", "slip_"});
  EXPECT_TRUE(foreign.empty()) << "an FEM scene allocated: " << join(foreign);
  std::cout << "  " << labels.size() << " View allocations in construction + 3 steps\n";
}

TEST(BuiltTerms, MpmSceneWithoutContactBuildsNoContactOrFriction) {
  std::unique_ptr<Simulation<2>> sim;
  const auto labels = allocations([&] {
    auto s = mpm_block_setup(0.2, Vec<2>(0.5, 0.5), 0.05, 4, 0.0, 1.0, TransferScheme::APIC);
    s.dt = 1e-3;
    s.gravity = {0.0, -9.81, 0.0};
    sim = std::make_unique<Simulation<2>>(s, comm());
    for (int k = 0; k < 3; ++k) sim->step();
  });
  EXPECT_EQ(sim->contact(), nullptr);
  EXPECT_EQ(sim->term_names(), std::vector<std::string>{"mpm elasticity"});
  const auto foreign = with_prefix(labels, {"contact_", "friction_", "bfemp_"});
  EXPECT_TRUE(foreign.empty()) << "an MPM scene without contact allocated: " << join(foreign);
}

// After the first step (graph, factorisation, work vectors), the steps of an
// FEM scene allocate none of bfemp's Views: the DOF space's graph and the
// Newton vectors are kept, nothing is rebuilt per step or per iteration.
TEST(BuiltTerms, FemStepsAfterTheFirstAllocateNoBfempView) {
  Simulation<2> sim(fem_scene(), comm());
  sim.step();
  long iterations = 0;
  const auto labels = allocations([&] {
    for (int k = 0; k < 4; ++k) iterations += sim.step().newton.iterations;
  });
  const auto own = with_prefix(labels, {"newton_", "fem_", "sys_", "dof_", "mpm_", "contact_", "friction_", "bfemp_"});
  EXPECT_TRUE(own.empty()) << "steps 2-5 allocated: " << join(own);
  EXPECT_GT(iterations, 4);
  std::cout << "  steps 2-5: " << iterations << " Newton iterations, " << labels.size()
            << " View allocations in all (Tpetra/Amesos2 internals included)\n";
}
