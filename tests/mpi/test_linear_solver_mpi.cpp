// The linear-solver layer on a distributed SPD matrix: CG + Ifpack2 or MueLu gives the
// same answer on 1 and 2 MPI ranks (both runs are checked against the same
// exact solution), direct solvers are exact on 1 rank and refused on 2.
#include <gtest/gtest.h>

#include <Tpetra_Core.hpp>
#include <Tpetra_CrsMatrix.hpp>
#include <Tpetra_Vector.hpp>
#include <cmath>
#include <iostream>

#include "solver/linear_solver.hpp"
#include "solver/solver_error.hpp"

using namespace bfemp;

namespace {

constexpr int kN = 60;  // grid side: kN^2 unknowns

// 2D 5-point Laplacian + mass shift on a contiguous row map.
Teuchos::RCP<Matrix> laplacian(const Teuchos::RCP<const Comm>& comm) {
  auto map = Teuchos::rcp(new Map(kN * kN, 0, comm));
  auto A = Teuchos::rcp(new Matrix(map, 5));
  for (LO l = 0; l < static_cast<LO>(map->getNodeNumElements()); ++l) {
    const GO r = map->getGlobalElement(l);
    const GO i = r % kN, j = r / kN;
    std::vector<GO> cols{r};
    std::vector<double> vals{4.0 + 1e-2};
    if (i > 0) cols.push_back(r - 1), vals.push_back(-1);
    if (i < kN - 1) cols.push_back(r + 1), vals.push_back(-1);
    if (j > 0) cols.push_back(r - kN), vals.push_back(-1);
    if (j < kN - 1) cols.push_back(r + kN), vals.push_back(-1);
    A->insertGlobalValues(r, Teuchos::ArrayView<const GO>(cols), Teuchos::ArrayView<const double>(vals));
  }
  A->fillComplete();
  return A;
}

double exact(GO r) { return std::sin(0.1 * static_cast<double>(r)) + 0.01 * static_cast<double>(r % 7); }

// Solves A x = A x_exact; returns max |x - x_exact| over all ranks.
double solve_error(const std::string& type, const std::string& prec) {
  auto comm = Tpetra::getDefaultComm();
  auto A = laplacian(comm);
  Vector xe(A->getRowMap()), b(A->getRowMap()), x(A->getRowMap());
  {
    auto v = xe.getLocalViewHost(Tpetra::Access::OverwriteAll);
    for (LO l = 0; l < static_cast<LO>(v.extent(0)); ++l) v(l, 0) = exact(A->getRowMap()->getGlobalElement(l));
  }
  A->apply(xe, b);
  auto p = linear_solver_schema()->sublist("CG");  // schema defaults
  Teuchos::ParameterList ls("Linear Solver");
  ls.set("type", type);
  ls.set("CG", p);
  ls.sublist("CG").set("preconditioner", prec);
  ls.sublist("CG").set("tolerance", 1e-12);
  if (prec == "RELAXATION") ls.sublist("CG").sublist("Ifpack2").set("relaxation: type", "Symmetric Gauss-Seidel");
  LinearSolver solver(ls, comm);
  solver.set_matrix(A);
  const auto st = solver.solve(b, x);
  EXPECT_GE(st.iterations, 1);
  x.update(-1.0, xe, 1.0);
  return x.normInf();
}

}  // namespace

TEST(LinearSolverMpi, CgWithIfpack2OrMueLuMatchesExactSolutionOnAnyRankCount) {
  for (const char* prec : {"RELAXATION", "SCHWARZ", "CHEBYSHEV", "MUELU", "BLOCK_CHOLMOD", "NONE"}) {
    const double err = solve_error("CG", prec);
    // |x - x_exact| <= cond(A) * tol * |x|; cond ~ 8 / 1e-2 here.
    EXPECT_LT(err, 1e-8) << prec << " on " << Tpetra::getDefaultComm()->getSize() << " rank(s)";
  }
}

// bfemp hands the solver its matrix when the graph is built (values still
// zero) and fills the values before each solve. SCHWARZ with an exact
// subdomain solve (AMESOS2: KLU2) must factor the values of solve time:
// on 1 rank it is then the exact inverse (CG in one iteration), on 2 ranks
// block Jacobi with exact blocks. Ifpack2 13.2 copies the values in
// initialize(): a factor of the zeros fails, a stale factor needs many
// iterations.
TEST(LinearSolverMpi, SchwarzSubdomainDirectSolveFactorsTheValuesOfSolveTime) {
  auto comm = Tpetra::getDefaultComm();
  auto A = laplacian(comm);
  auto values = [&](double scale_diag, double off) {
    A->resumeFill();
    for (LO l = 0; l < static_cast<LO>(A->getRowMap()->getNodeNumElements()); ++l) {
      const GO r = A->getRowMap()->getGlobalElement(l);
      const GO i = r % kN, j = r / kN;
      std::vector<GO> cols{r};
      std::vector<double> vals{scale_diag * (4.0 + 1e-2) + 0.05 * static_cast<double>(r % 5)};
      if (i > 0) cols.push_back(r - 1), vals.push_back(-off);
      if (i < kN - 1) cols.push_back(r + 1), vals.push_back(-off);
      if (j > 0) cols.push_back(r - kN), vals.push_back(-off);
      if (j < kN - 1) cols.push_back(r + kN), vals.push_back(-off);
      A->replaceGlobalValues(r, Teuchos::ArrayView<const GO>(cols), Teuchos::ArrayView<const double>(vals));
    }
    A->fillComplete();
  };
  values(0.0, 0.0);  // the graph with zero values, as at a graph build
  Teuchos::ParameterList ls = *linear_solver_schema();
  ls.set("type", std::string("CG"));
  ls.sublist("CG").set("preconditioner", std::string("SCHWARZ"));
  ls.sublist("CG").set("tolerance", 1e-12);
  auto& ip = ls.sublist("CG").sublist("Ifpack2");
  ip.set("schwarz: inner preconditioner name", std::string("AMESOS2"));
  ip.sublist("schwarz: inner preconditioner parameters").set("Amesos2 solver name", std::string("KLU2"));
  ip.sublist("schwarz: inner preconditioner parameters").sublist("Amesos2");
  LinearSolver solver(ls, comm);
  solver.set_matrix(A);
  // Two different operators on one graph, as two Newton iterations.
  for (const auto& [diag, off] : {std::pair{1.0, 1.0}, std::pair{1.5, 0.5}}) {
    values(diag, off);
    Vector xe(A->getRowMap()), b(A->getRowMap()), x(A->getRowMap());
    {
      auto v = xe.getLocalViewHost(Tpetra::Access::OverwriteAll);
      for (LO l = 0; l < static_cast<LO>(v.extent(0)); ++l) v(l, 0) = exact(A->getRowMap()->getGlobalElement(l));
    }
    A->apply(xe, b);
    const auto st = solver.solve(b, x);
    x.update(-1.0, xe, 1.0);
    EXPECT_LT(x.normInf(), 1e-8) << "diagonal x" << diag;
    // 1 rank: the subdomain is the whole matrix. 2 ranks: two exact blocks
    // of a 60 x 60 grid cut in half; relaxation needs ~100 iterations.
    EXPECT_LE(st.iterations, comm->getSize() == 1 ? 2 : 40) << "diagonal x" << diag;
  }
}

// BLOCK_CHOLMOD: each rank's diagonal block factorised exactly, with the
// values of solve time. 1 rank: M = A, CG in one iteration. P ranks: the
// 60 x 60 grid cut in P row slabs; CG resolves the coupling along the cuts
// in fewer iterations than CG + symmetric Gauss-Seidel where A is badly
// conditioned (diagonal 4.01, cond ~ 800; measured 30 against 47 on 2 and 3
// ranks); on the well conditioned second matrix both need few (8 and 9).
// An indefinite matrix is
// reported as NotPositiveDefinite on every rank (so no rank waits in CG).
TEST(LinearSolverMpi, BlockCholmodFactorsEachRanksBlockWithTheValuesOfSolveTime) {
  auto comm = Tpetra::getDefaultComm();
  auto A = laplacian(comm);
  auto values = [&](double diag, double off) {
    A->resumeFill();
    for (LO l = 0; l < static_cast<LO>(A->getRowMap()->getNodeNumElements()); ++l) {
      const GO r = A->getRowMap()->getGlobalElement(l);
      const GO i = r % kN, j = r / kN;
      std::vector<GO> cols{r};
      std::vector<double> vals{diag + 0.05 * static_cast<double>(r % 5)};
      if (i > 0) cols.push_back(r - 1), vals.push_back(-off);
      if (i < kN - 1) cols.push_back(r + 1), vals.push_back(-off);
      if (j > 0) cols.push_back(r - kN), vals.push_back(-off);
      if (j < kN - 1) cols.push_back(r + kN), vals.push_back(-off);
      A->replaceGlobalValues(r, Teuchos::ArrayView<const GO>(cols), Teuchos::ArrayView<const double>(vals));
    }
    A->fillComplete();
  };
  values(0.0, 0.0);  // the graph with zero values, as at a graph build
  Teuchos::ParameterList ls = *linear_solver_schema();
  ls.set("type", std::string("CG"));
  ls.sublist("CG").set("preconditioner", std::string("BLOCK_CHOLMOD"));
  ls.sublist("CG").set("tolerance", 1e-12);
  LinearSolver solver(ls, comm);
  solver.set_matrix(A);
  Teuchos::ParameterList lr = ls;  // the reference: CG + symmetric Gauss-Seidel
  lr.sublist("CG").set("preconditioner", std::string("RELAXATION"));
  lr.sublist("CG").sublist("Ifpack2").set("relaxation: type", std::string("Symmetric Gauss-Seidel"));
  LinearSolver relaxation(lr, comm);
  relaxation.set_matrix(A);
  for (const auto& [diag, off] : {std::pair{4.01, 1.0}, std::pair{6.0, 0.5}}) {
    values(diag, off);
    Vector xe(A->getRowMap()), b(A->getRowMap()), x(A->getRowMap());
    {
      auto v = xe.getLocalViewHost(Tpetra::Access::OverwriteAll);
      for (LO l = 0; l < static_cast<LO>(v.extent(0)); ++l) v(l, 0) = exact(A->getRowMap()->getGlobalElement(l));
    }
    A->apply(xe, b);
    const auto st = solver.solve(b, x);
    x.update(-1.0, xe, 1.0);
    EXPECT_LT(x.normInf(), 1e-8) << "diagonal " << diag;
    Vector xr(A->getRowMap());
    const auto sr = relaxation.solve(b, xr);
    if (comm->getSize() == 1)
      EXPECT_EQ(st.iterations, 1) << "diagonal " << diag;
    else if (diag < 5)  // badly conditioned (1e3): exact blocks leave only the cuts' coupling
      EXPECT_LT(st.iterations, sr.iterations) << "diagonal " << diag;
    std::cout << "diagonal " << diag << ": " << st.iterations << " CG iterations, " << sr.iterations
              << " with symmetric Gauss-Seidel\n";
  }
  // Indefinite: a negative diagonal entry in rank 0's rows only.
  A->resumeFill();
  if (comm->getRank() == 0) {
    const GO r = A->getRowMap()->getGlobalElement(0);
    std::vector<GO> c{r};
    std::vector<double> v{-1.0};
    A->replaceGlobalValues(r, Teuchos::ArrayView<const GO>(c), Teuchos::ArrayView<const double>(v));
  }
  A->fillComplete();
  Vector b(A->getRowMap()), x(A->getRowMap());
  b.putScalar(1.0);
  EXPECT_THROW(solver.solve(b, x), NotPositiveDefinite) << "on rank " << comm->getRank();
}

TEST(LinearSolverMpi, DirectSolversExactOnOneRankRefusedOnMore) {
  auto comm = Tpetra::getDefaultComm();
  for (const char* type : {"Cholmod", "KLU2"}) {
    if (comm->getSize() == 1) {
      EXPECT_LT(solve_error(type, "NONE"), 1e-10) << type;
    } else {
      Teuchos::ParameterList ls = *linear_solver_schema();
      ls.set("type", std::string(type));
      try {
        LinearSolver s(ls, comm);
        ADD_FAILURE() << type << " accepted on " << comm->getSize() << " ranks";
      } catch (const std::invalid_argument& e) {
        const std::string msg = e.what();
        EXPECT_NE(msg.find("Linear Solver/type"), std::string::npos) << msg;
        EXPECT_NE(msg.find(type), std::string::npos) << msg;
        EXPECT_NE(msg.find("1 MPI rank"), std::string::npos) << msg;
      }
    }
  }
}

TEST(LinearSolverMpi, CgNonConvergenceIsAnError) {
  auto comm = Tpetra::getDefaultComm();
  auto A = laplacian(comm);
  Vector b(A->getRowMap()), x(A->getRowMap());
  b.putScalar(1.0);
  Teuchos::ParameterList ls = *linear_solver_schema();
  ls.set("type", std::string("CG"));
  ls.sublist("CG").set("max iterations", 3);
  ls.sublist("CG").set("preconditioner", std::string("NONE"));
  LinearSolver s(ls, comm);
  s.set_matrix(A);
  EXPECT_THROW(s.solve(b, x), SolverError);
}

TEST(LinearSolverMpi, MisspelledMueLuKeyRefusedOnAnyRankCount) {
  auto comm = Tpetra::getDefaultComm();
  Teuchos::ParameterList ls = *linear_solver_schema();
  ls.set("type", std::string("CG"));
  ls.sublist("CG").set("preconditioner", std::string("MUELU"));
  ls.sublist("CG").sublist("MueLu").set("aggregation: typo", 3);
  try {
    LinearSolver s(ls, comm);
    ADD_FAILURE() << "accepted on " << comm->getSize() << " ranks";
  } catch (const std::invalid_argument& e) {
    const std::string msg = e.what();
    EXPECT_NE(msg.find("Linear Solver/CG/MueLu"), std::string::npos) << msg;
    EXPECT_NE(msg.find("aggregation: typo"), std::string::npos) << msg;
  }
}
