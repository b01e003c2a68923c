// The strict finite-difference check (tests/common/fd_check.hpp) against a
// term with known derivatives and deliberate bugs: it passes the correct
// term, and fails each of: a small block wrong by 1 % next to entries 1e5
// times larger (which a check relative to the largest entry cannot see), a
// Hessian entry missing from the graph, free-prescribed couplings left in
// the matrix instead of the right-hand side, a prescribed row assembled, and
// the right-hand side without the scale factor.
#include <gtest/gtest-spi.h>
#include <gtest/gtest.h>

#include <string>
#include <vector>

#include "common/fd_check.hpp"

using namespace bfemp;

namespace {

static_assert(Kokkos::SpaceAccessibility<Kokkos::HostSpace, MemSpace>::accessible,
              "the test term runs its loops on the host");

enum class Bug { none, small_block, missing_coupling, prescribed_column_in_matrix, prescribed_row, rhs_without_scale };

// E(x) = 1/2 x^T K x + sum_i c_i x_i^4 / 4 on 4 nodes in 2D (8 DOFs): nodes
// 0-1 coupled stiffly (~1e3), nodes 2-3 weakly (~1e-2), all nodes to each other.
class TestTerm : public EnergyTerm<2> {
 public:
  static constexpr int nd = 8;
  explicit TestTerm(Bug bug) : bug_(bug) {
    for (int i = 0; i < nd; ++i)
      for (int j = 0; j < nd; ++j) {
        const int a = i / 2, b = j / 2;
        double k = 0.1 * std::cos(1.0 + i + 2.0 * j) * std::cos(1.0 + j + 2.0 * i);  // symmetric
        if (a < 2 && b < 2) k *= 1e4;                                               // stiff block
        if (a >= 2 && b >= 2) k *= 0.1;                                             // weak block (~1e-2)
        K_[i][j] = k + (i == j ? (a < 2 ? 2e3 : 0.05) : 0.0);
      }
    for (int i = 0; i < nd; ++i) c_[i] = 0.3 + 0.1 * i;
  }
  std::string name() const override { return "test"; }
  // Nodes 0..3 all coupled, but for the missing_coupling bug: (2, 3) and (3, 2).
  void add_couplings(NodeGraphBuilder& graph) const override {
    const bool missing = bug_ == Bug::missing_coupling;
    graph.add_products(
        4, 1, 4, KOKKOS_LAMBDA(const long s, int) { return LO(s); },
        KOKKOS_LAMBDA(const long s, const int b) {
          return missing && ((s == 2 && b == 3) || (s == 3 && b == 2)) ? LO(-1) : LO(b);
        });
  }
  double energy(ConstDofView x) const override {
    double e = 0;
    for (int i = 0; i < nd; ++i) {
      for (int j = 0; j < nd; ++j) e += 0.5 * x(i) * K_[i][j] * x(j);
      e += c_[i] * std::pow(x(i), 4) / 4;
    }
    return e;
  }
  void gradient(ConstDofView x, double scale, DofView grad) const override {
    for (int i = 0; i < nd; ++i) grad(i) += scale * g(x, i);
  }
  // Writes into the sink's matrix and vectors itself (not through
  // add_stencil), so that each bug below can break one elimination rule.
  void assemble(ConstDofView x, const Sink<2>& sink) const override {
    const double scale = sink.scale;
    const auto& A = sink.A;
    const auto& prescribed = sink.prescribed;
    const auto& dx_prescribed = sink.dx_prescribed;
    const auto& rhs = sink.rhs;
    gradient(x, scale, sink.grad);
    for (int i = 0; i < nd; ++i) {
      if (prescribed(i) && bug_ != Bug::prescribed_row) continue;
      for (int j = 0; j < nd; ++j) {
        double h = scale * H(x, i, j);
        if (bug_ == Bug::small_block && i / 2 >= 2 && j / 2 >= 2 && i / 2 != j / 2) h *= 1.01;
        if (prescribed(j) && bug_ != Bug::prescribed_column_in_matrix) {
          rhs(i) -= (bug_ == Bug::rhs_without_scale ? h / scale : h) * dx_prescribed(j);
        } else {
          const LO col = j;
          A.sumIntoValues(i, &col, 1, &h, false, false);
        }
      }
    }
  }
  double max_step(ConstDofView, ConstDofView) const override { return INFINITY; }

 private:
  double g(ConstDofView x, int i) const {
    double v = c_[i] * std::pow(x(i), 3);
    for (int j = 0; j < nd; ++j) v += K_[i][j] * x(j);
    return v;
  }
  double H(ConstDofView x, int i, int j) const { return K_[i][j] + (i == j ? 3 * c_[i] * x(i) * x(i) : 0.0); }
  Bug bug_;
  double K_[nd][nd], c_[nd];
};

// Failure messages of check_energy_term on the term (fatal or not).
std::vector<std::string> failures_of(Bug bug) {
  TestTerm term(bug);
  Kokkos::View<double*, MemSpace> x("x", TestTerm::nd);
  for (int i = 0; i < TestTerm::nd; ++i) x(i) = 0.1 * (i + 1) * (i % 2 ? -1 : 1);
  // Prescribed: DOF 1 (stiff node 0) and node 3 (weak block), as a mask.
  std::vector<int> mask{0, 1, 0, 0, 0, 0, 1, 1};
  testing::TestPartResultArray results;
  {
    testing::ScopedFakeTestPartResultReporter reporter(testing::ScopedFakeTestPartResultReporter::INTERCEPT_ONLY_CURRENT_THREAD,
                                                       &results);
    fixtures::check_energy_term<2>(term, 4, x, 1e-6, 1e-6, mask);
  }
  std::vector<std::string> out;
  for (int i = 0; i < results.size(); ++i)
    if (results.GetTestPartResult(i).failed()) out.push_back(results.GetTestPartResult(i).message());
  return out;
}

bool any_contains(const std::vector<std::string>& v, const std::string& s) {
  for (const auto& m : v)
    if (m.find(s) != std::string::npos) return true;
  return false;
}

std::string joined(const std::vector<std::string>& v) {
  std::string s;
  for (const auto& m : v) s += m + "\n";
  return s;
}

}  // namespace

TEST(FdCheck, PassesTheCorrectTerm) {
  const auto f = failures_of(Bug::none);
  EXPECT_TRUE(f.empty()) << joined(f);
}

TEST(FdCheck, SeesASmallWrongBlockNextToLargeEntries) {
  const auto f = failures_of(Bug::small_block);
  EXPECT_TRUE(any_contains(f, "Hessian: ")) << joined(f);  // the all-free variant
}

TEST(FdCheck, SeesAnEntryMissingFromTheGraph) {
  const auto f = failures_of(Bug::missing_coupling);
  EXPECT_TRUE(any_contains(f, "Hessian: ")) << joined(f);
}

TEST(FdCheck, SeesPrescribedCouplingsLeftInTheMatrix) {
  const auto f = failures_of(Bug::prescribed_column_in_matrix);
  EXPECT_TRUE(any_contains(f, "entries of prescribed rows / columns (must be 0)")) << joined(f);
  EXPECT_TRUE(any_contains(f, "rhs = -scale H(free, prescribed) dx_prescribed")) << joined(f);
}

TEST(FdCheck, SeesAnAssembledPrescribedRow) {
  const auto f = failures_of(Bug::prescribed_row);
  EXPECT_TRUE(any_contains(f, "entries of prescribed rows / columns (must be 0)")) << joined(f);
}

TEST(FdCheck, SeesTheRhsWithoutTheScale) {
  const auto f = failures_of(Bug::rhs_without_scale);
  EXPECT_TRUE(any_contains(f, "rhs = -scale H(free, prescribed) dx_prescribed")) << joined(f);
  EXPECT_FALSE(any_contains(f, "Hessian")) << joined(f);
}
