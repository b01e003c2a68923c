#pragma once
// Algebraic multigrid for Belos CG: a MueLu hierarchy (aggregation on the
// rigid-body modes; by default unsmoothed, with P and R kept across solves:
// the fastest of the variants measured, see with_defaults) built on the
// Newton matrix A.
//
// Near-null space. For elasticity the smooth error of A lies near the rigid-
// body modes of the nodes, and aggregation AMG interpolates exactly the
// vectors it is given: with node positions x_a (node-interleaved DOFs
// a dim + c), the modes are the translations t_k (1 in component k) and the
// infinitesimal rotations r = omega x (x_a - x_c) about the centroid x_c:
// 2D: 2 translations + 1 rotation (-(y-yc), x-xc); 3D: 3 + 3. They are passed
// as MueLu's "user data/Nullspace" with "number of equations" = dim.
// Without them MueLu uses the constant vector per equation.
//
// Set-up cost: the hierarchy is created on the first compute() after a new
// matrix graph or near-null space; later compute() calls (new values on the
// same graph: the next Newton iteration or step) go through
// MueLu::ReuseTpetraPreconditioner, which keeps what "reuse: type" says
// ("none": rebuild all levels; "tP": keep the aggregates and the tentative
// prolongator; "RP", bfemp's default: keep P and R, recompute the coarse
// operators and smoothers; see the MueLu user guide). The Newton solver hands
// new modes (hence a new hierarchy) after a graph rebuild and every
// 'Linear Solver/CG/MueLu rebuild every' solves.
//
// Coarse solve: MueLu's Amesos2 KLU2 on 1 rank; on more ranks 4 symmetric
// Gauss-Seidel sweeps (KLU2 is wrong on several ranks in Trilinos 13.2), unless
// the scene sets 'coarse: type'.
#include <Teuchos_ParameterList.hpp>
#include <Teuchos_RCP.hpp>
#include <memory>
#include <string>

#include "solver/tpetra_types.hpp"

namespace bfemp {

class MueLuPreconditioner {
 public:
  // `user`: the scene's 'Linear Solver/CG/MueLu' list. Its keys are checked
  // here, on a small matrix, so a misspelled key stops before the first step
  // (std::invalid_argument naming the key path).
  MueLuPreconditioner(const Teuchos::ParameterList& user, const Teuchos::RCP<const Comm>& comm);
  ~MueLuPreconditioner();
  MueLuPreconditioner(const MueLuPreconditioner&) = delete;
  MueLuPreconditioner& operator=(const MueLuPreconditioner&) = delete;

  void set_matrix(const Teuchos::RCP<const Matrix>& A);
  // Rigid-body modes (columns) on A's row map; block_size = dim.
  void set_near_null_space(const Teuchos::RCP<MultiVec>& modes, int block_size);
  // Builds or refreshes the hierarchy for A's current values.
  void compute();
  Teuchos::RCP<Operator> op() const;
  // Levels of the last hierarchy (0 before the first compute).
  int levels() const;
  int setups() const { return setups_; }
  std::string describe() const;
  int reuses() const { return reuses_; }

 private:
  struct Impl;
  std::unique_ptr<Impl> impl_;
  int setups_ = 0, reuses_ = 0;
};

// Fills `modes` (dim == 2: 3 columns, dim == 3: 6) with the rigid-body modes
// of the node positions x (node-interleaved; its first rows are the modes'
// local rows: the owned nodes come first).
template <int dim>
void rigid_body_modes(Kokkos::View<const double*, MemSpace> x, MultiVec& modes);

}  // namespace bfemp
