#include "solver/muelu_preconditioner.hpp"

#include <MueLu_CreateTpetraPreconditioner.hpp>
#include <Teuchos_DefaultMpiComm.hpp>
#include <mpi.h>
#include <Tpetra_CrsMatrix.hpp>
#include <Tpetra_MultiVector.hpp>
#include <sstream>
#include <stdexcept>

namespace bfemp {

using Teuchos::RCP;
using Teuchos::rcp;
using MueLuOp = MueLu::TpetraOperator<double, LO, GO, Node>;

namespace {

// bfemp's defaults under the user's keys (the user's win). On more than one
// rank the coarse solve is 4 symmetric Gauss-Seidel sweeps instead of
// MueLu's default Amesos2 KLU2, which returns wrong solutions on several
// ranks in Trilinos 13.2 (../shared/TRILINOS.md §10; CG then stalls).
Teuchos::ParameterList with_defaults(const Teuchos::ParameterList& user, int ranks) {
  Teuchos::ParameterList p("MueLu");
  p.set("verbosity", "none");
  // Measured on the clamped blocks of perf/bench_newton (1e5 DOFs, 1 thread,
  // per Newton iteration): unsmoothed aggregation with P and R kept across
  // solves costs 0.81 s (2D) and 3.1 s (3D), against 1.56 s and 19.9 s for
  // smoothed aggregation rebuilt every solve (its RAP with 6 modes per
  // aggregate dominates in 3D), 6.05 s and 4.49 s for Ifpack2 Chebyshev.
  p.set("multigrid algorithm", "unsmoothed");
  p.set("reuse: type", "RP");
  if (ranks > 1 && !user.isParameter("coarse: type")) {
    p.set("coarse: type", "RELAXATION");
    auto& cp = p.sublist("coarse: params");
    cp.set("relaxation: type", "Symmetric Gauss-Seidel");
    cp.set("relaxation: sweeps", 4);
  }
  p.setParameters(user);
  return p;
}

std::string first_line(const std::string& s) {
  // MueLu's messages carry file and line first; keep the part that names the key.
  std::string out = s;
  const auto pos = out.find("Unknown");
  if (pos != std::string::npos) out = out.substr(pos);
  while (!out.empty() && (out.back() == '\n' || out.back() == ' ')) out.pop_back();
  return out;
}

}  // namespace

struct MueLuPreconditioner::Impl {
  RCP<const Comm> comm;
  Teuchos::ParameterList params;
  RCP<const Matrix> A;
  RCP<MultiVec> modes;
  int block_size = 1;
  RCP<MueLuOp> prec;
  bool fresh = true;  // next compute() creates the hierarchy
};

MueLuPreconditioner::MueLuPreconditioner(const Teuchos::ParameterList& user,
                                         const RCP<const Comm>& comm)
    : impl_(new Impl) {
  impl_->comm = comm;
  impl_->params = with_defaults(user, comm->getSize());
  // Check the list on a 4-row diagonal matrix on this rank alone: MueLu
  // validates every key against its master list when it builds.
  // (an MpiComm over MPI_COMM_SELF: MueLu's statistics cast the comm to an
  // MpiComm and crash on a SerialComm)
  RCP<const Comm> self = rcp(new Teuchos::MpiComm<int>(MPI_COMM_SELF));
  auto map = rcp(new Map(4, 0, self));
  auto D = rcp(new Matrix(map, 1));
  for (GO r = 0; r < 4; ++r) {
    const double one = 1.0;
    D->insertGlobalValues(r, Teuchos::ArrayView<const GO>(&r, 1), Teuchos::ArrayView<const double>(&one, 1));
  }
  D->fillComplete();
  Teuchos::ParameterList trial = impl_->params;
  try {
    RCP<Operator> op = D;
    (void)MueLu::CreateTpetraPreconditioner<double, LO, GO, Node>(op, trial);
  } catch (const std::exception& e) {
    throw std::invalid_argument("scene sublist 'Linear Solver/CG/MueLu' rejected by MueLu: " +
                                first_line(e.what()));
  }
}

MueLuPreconditioner::~MueLuPreconditioner() = default;

void MueLuPreconditioner::set_matrix(const RCP<const Matrix>& A) {
  impl_->A = A;
  impl_->fresh = true;
}

void MueLuPreconditioner::set_near_null_space(const RCP<MultiVec>& modes, int block_size) {
  impl_->modes = modes;
  impl_->block_size = block_size;
  impl_->fresh = true;
}

void MueLuPreconditioner::compute() {
  auto& m = *impl_;
  if (m.A.is_null()) throw std::logic_error("MueLuPreconditioner::compute before set_matrix");
  auto A = Teuchos::rcp_const_cast<Matrix>(m.A);
  if (m.fresh || m.prec.is_null()) {
    Teuchos::ParameterList p = m.params;
    if (!m.modes.is_null()) {
      if (!p.isParameter("number of equations")) p.set("number of equations", m.block_size);
      p.sublist("user data").set("Nullspace", m.modes);
    }
    RCP<Operator> op = A;
    m.prec = MueLu::CreateTpetraPreconditioner<double, LO, GO, Node>(op, p);
    m.fresh = false;
    ++setups_;
  } else {
    MueLu::ReuseTpetraPreconditioner<double, LO, GO, Node>(A, *m.prec);
    ++reuses_;
  }
}

RCP<Operator> MueLuPreconditioner::op() const { return impl_->prec; }

std::string MueLuPreconditioner::describe() const {
  const auto& p = impl_->params;
  std::string coarse = p.isParameter("coarse: type") ? p.get<std::string>("coarse: type") : "KLU2";
  return "MueLu (" + p.get<std::string>("multigrid algorithm") + " aggregation on the rigid-body modes, reuse " +
         p.get<std::string>("reuse: type") + ", coarse " + coarse + ")";
}

int MueLuPreconditioner::levels() const {
  if (impl_->prec.is_null()) return 0;
  auto h = impl_->prec->GetHierarchy();
  return h.is_null() ? 0 : h->GetNumLevels();
}

template <int dim>
void rigid_body_modes(Kokkos::View<const double*, MemSpace> x, MultiVec& modes) {
  constexpr int nm = dim == 2 ? 3 : 6;
  if (static_cast<int>(modes.getNumVectors()) != nm)
    throw std::logic_error("rigid_body_modes: wrong column count");
  // The modes' map holds this rank's owned nodes, the first ones of x (the
  // caller passes them so).
  const LO n_nodes = static_cast<LO>(modes.getLocalLength() / dim);
  if (static_cast<std::size_t>(n_nodes) * dim > x.extent(0))
    throw std::logic_error("rigid_body_modes: fewer positions than the modes' rows");
  // Centroid over this rank's nodes (a shift of the rotation centre adds
  // translations, which are in the span anyway; it keeps the columns well
  // scaled).
  double c[3] = {0, 0, 0};
  for (int k = 0; k < dim; ++k) {
    double s = 0;
    Kokkos::parallel_reduce(
        "rbm_centroid", Kokkos::RangePolicy<ExecSpace>(0, n_nodes),
        KOKKOS_LAMBDA(const LO a, double& acc) { acc += x(a * dim + k); }, s);
    c[k] = n_nodes > 0 ? s / n_nodes : 0.0;
  }
  const double cx = c[0], cy = c[1], cz = c[2];
  auto v = modes.getLocalViewDevice(Tpetra::Access::OverwriteAll);
  Kokkos::parallel_for(
      "rbm_fill", Kokkos::RangePolicy<ExecSpace>(0, n_nodes), KOKKOS_LAMBDA(const LO a) {
        const LO i = a * dim;
        for (int r = 0; r < dim; ++r)
          for (int k = 0; k < nm; ++k) v(i + r, k) = 0.0;
        for (int r = 0; r < dim; ++r) v(i + r, r) = 1.0;
        const double X = x(i) - cx, Y = x(i + 1) - cy;
        if constexpr (dim == 2) {
          v(i, 2) = -Y;
          v(i + 1, 2) = X;
        } else {
          const double Z = x(i + 2) - cz;
          // omega = e_z, e_x, e_y: omega x (X, Y, Z)
          v(i, 3) = -Y, v(i + 1, 3) = X;
          v(i + 1, 4) = -Z, v(i + 2, 4) = Y;
          v(i, 5) = Z, v(i + 2, 5) = -X;
        }
      });
  (void)cz;
}

template void rigid_body_modes<2>(Kokkos::View<const double*, MemSpace>, MultiVec&);
template void rigid_body_modes<3>(Kokkos::View<const double*, MemSpace>, MultiVec&);

}  // namespace bfemp
