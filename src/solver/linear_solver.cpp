#include "solver/linear_solver.hpp"

#include <algorithm>
#include <cmath>

#include <Amesos2.hpp>
#include <BelosLinearProblem.hpp>
#include <BelosPseudoBlockCGSolMgr.hpp>
#include <BelosTpetraAdapter.hpp>
#include <Ifpack2_Factory.hpp>
#include <Teuchos_StandardParameterEntryValidators.hpp>
#include <Tpetra_CrsMatrix.hpp>
#include <Tpetra_Vector.hpp>
#include <set>
#include <sstream>

#include "solver/block_cholmod.hpp"
#include "solver/cholmod_direct.hpp"
#include "solver/muelu_preconditioner.hpp"
#include "solver/solver_error.hpp"

namespace bfemp {
namespace {

using Teuchos::ParameterList;
using Teuchos::RCP;
using Teuchos::rcp;

const char* const kPrecNames[] = {"RELAXATION", "CHEBYSHEV", "RILUK", "SCHWARZ", "MUELU", "BLOCK_CHOLMOD", "NONE"};

// Ifpack2 validates only RELAXATION's list; the others ignore unknown keys, so
// bfemp checks those against the keys each one reads (Ifpack2 13.2 sources).
const std::set<std::string>& known_ifpack2_keys(const std::string& prec) {
  static const std::set<std::string> cheb = {
      "chebyshev: degree", "chebyshev: ratio eigenvalue", "chebyshev: min eigenvalue",
      "chebyshev: max eigenvalue", "chebyshev: eigenvalue max iterations",
      "chebyshev: assume matrix does not change", "chebyshev: zero starting solution",
      "chebyshev: min diagonal value", "chebyshev: boost factor", "chebyshev: algorithm"};
  static const std::set<std::string> riluk = {
      "fact: iluk level-of-fill", "fact: relax value", "fact: absolute threshold",
      "fact: relative threshold", "fact: type", "fact: iluk overalloc"};
  static const std::set<std::string> schwarz = {
      "schwarz: overlap level", "schwarz: inner preconditioner name",
      "schwarz: inner preconditioner parameters", "schwarz: combine mode",
      "schwarz: use reordering", "schwarz: reordering list", "schwarz: subdomain id",
      "schwarz: filter singletons", "schwarz: num iterations", "schwarz: zero starting solution"};
  static const std::set<std::string> none;
  if (prec == "CHEBYSHEV") return cheb;
  if (prec == "RILUK") return riluk;
  if (prec == "SCHWARZ") return schwarz;
  return none;
}

void check_ifpack2_keys(const std::string& prec, const ParameterList& list) {
  if (prec == "RELAXATION" || prec == "NONE") return;  // RELAXATION validates itself
  const auto& known = known_ifpack2_keys(prec);
  for (auto it = list.begin(); it != list.end(); ++it) {
    const std::string& key = list.name(it);
    if (!known.count(key)) {
      std::ostringstream msg;
      msg << "scene key 'Linear Solver/CG/Ifpack2/" << key << "': not a parameter of the "
          << prec << " preconditioner; expected one of:";
      for (const auto& k : known) msg << " '" << k << "'";
      throw std::invalid_argument(msg.str());
    }
  }
}

}  // namespace

// Default of 'Linear Solver/Cholmod/reuse iterations'. Measured on the rings at
// the paper's size (11 steps, 85 Newton iterations, 1 thread): 8 / 12 / 20 / 30
// iterations gave 55 / 47 / 41 / 35 numeric factorisations and 3.46 / 3.04 /
// 2.70 / 2.84 s of linear solve, against 91 and 4.84 s with 0.
constexpr int kCholmodReuseIterations = 20;

Teuchos::RCP<const Teuchos::ParameterList> linear_solver_schema() {
  auto pl = rcp(new ParameterList("Linear Solver"));
  Teuchos::setStringToIntegralParameter<int>(
      "type", "Cholmod",
      "Cholmod or KLU2 (direct, 1 MPI rank only) or CG (Belos + Ifpack2 or MueLu)",
      Teuchos::tuple<std::string>("Cholmod", "KLU2", "CG"), pl.get());
  auto& ch = pl->sublist("Cholmod", false,
                         "Cholmod: reuse of the previous numeric factor within a time step (CG "
                         "preconditioned by it before a new factorisation; solver/cholmod_direct.hpp)");
  ch.set("reuse iterations", kCholmodReuseIterations,
         "CG iterations on the previous factor of the same graph before the matrix is factorised "
         "anew (CG also stops early when its rate cannot reach the tolerance within them); 0: "
         "factorise at every Newton iteration",
         rcp(new Teuchos::EnhancedNumberValidator<int>(0, 1000)));
  ch.set("reuse by cost", true,
         "raise the CG budget above 'reuse iterations' to one factorisation's cost in CG iterations, "
         "estimated from the symbolic analysis (flops / (4 (4 nnz(L) + 2 nnz(A))), at most 40; "
         "supernodal factors only; measured: 3D twist 25-27 (ci) and 84, capped to 40 (paper size), 2D rings 3)");
  ch.set("reuse tolerance", 1e-10,
         "relative residual |b - A x| / |b| that CG on the previous factor must reach (with "
         "'forcing term: adaptive', the tightest it is asked for)",
         rcp(new Teuchos::EnhancedNumberValidator<double>(1e-16, 1e-6)));
  Teuchos::setStringToIntegralParameter<int>(
      "forcing term", "adaptive",
      "adaptive: inexact Newton, CG on the previous factor stops at eta_k = min(0.1, |r_k| / |r_0|) "
      "(r: the Newton residual, floor 'reuse tolerance'), and a Newton iteration that converges "
      "on such a direction is confirmed with one solved to 'reuse tolerance' (paper-size twist, 5 "
      "steps: 13 -> 8 factorisations, 650 -> 364 CG iterations, wall 62 -> 50 s; 2D rings at the paper's "
      "size: linear solve 0.13 -> 0.095 s per contact step); fixed: always "
      "'reuse tolerance'",
      Teuchos::tuple<std::string>("adaptive", "fixed"), &ch);
  Teuchos::setStringToIntegralParameter<int>(
      "reuse precision", "single",
      "single: CG on the previous factor applies a float copy of it (double arithmetic; "
      "solver/single_factor.hpp), half the bytes per triangular solve; double: CHOLMOD's own "
      "solve on the double factor. The answer's tolerance is the same either way",
      Teuchos::tuple<std::string>("single", "double"), &ch);
  auto& cg = pl->sublist("CG", false,
                         "Belos conjugate gradients with an Ifpack2 or MueLu preconditioner");
  cg.set("tolerance", 1e-12,
         "relative residual |b - A x| / |b| at which CG stops (with 'forcing term: adaptive', the "
         "tightest it is asked for)",
         rcp(new Teuchos::EnhancedNumberValidator<double>(1e-16, 1e-1)));
  Teuchos::setStringToIntegralParameter<int>(
      "forcing term", "adaptive",
      "adaptive: inexact Newton, CG stops at eta_k = min(0.1, |r_k| / |r_0|) (r: the Newton "
      "residual, floor 'tolerance'); fixed: always at 'tolerance'",
      Teuchos::tuple<std::string>("adaptive", "fixed"), &cg);
  cg.set("MueLu rebuild every", 10,
         "MUELU: Newton solves (time steps) between new hierarchies built on the nodes' current "
         "rigid-body modes (also after every graph rebuild); in between the hierarchy is reused "
         "as 'MueLu/reuse: type' says",
         rcp(new Teuchos::EnhancedNumberValidator<int>(1, 1000000)));
  cg.set("max iterations", 2000, "CG iteration cap; reaching it is an error",
         rcp(new Teuchos::EnhancedNumberValidator<int>(1, 1000000)));
  // Default BLOCK_CHOLMOD, by measurement (perf/README.md): on the 3D twist
  // on 2 ranks (overlap 1 with reuse) 1.71-1.87 s per contact step against
  // 6.63-7.38 s with RELAXATION at the ci size, 3.82 s against 11.63 s
  // weak-scaled; on 1
  // rank it is one CG iteration on a Cholesky factor. MUELU (5x faster than
  // RELAXATION on FEM-only 2D blocks of 1e5 DOFs) pays a new hierarchy each
  // step where MPM bodies change the graph (A1 ci rings: linear solve 44 s
  // against 5.7 s with RELAXATION).
  Teuchos::setStringToIntegralParameter<int>(
      "preconditioner", "BLOCK_CHOLMOD",
      "an Ifpack2 preconditioner (RELAXATION, CHEBYSHEV, RILUK, SCHWARZ), MUELU (algebraic "
      "multigrid on the rigid-body modes of the nodes: the fastest for FEM-only scenes, slow "
      "where the graph changes every step, as with MPM bodies), BLOCK_CHOLMOD (an exact "
      "Cholesky factor of each rank's diagonal block: one iteration on 1 rank, the fewest on "
      "the 3D twist on 2) or NONE",
      Teuchos::tuple<std::string>(kPrecNames[0], kPrecNames[1], kPrecNames[2], kPrecNames[3],
                                  kPrecNames[4], kPrecNames[5], kPrecNames[6]),
      &cg);
  cg.set("block overlap", 1,
         "BLOCK_CHOLMOD: 0, each rank factorises its owned rows (block Jacobi); 1, its owned rows "
         "and the ghost rows they couple to (additive Schwarz: fewer CG iterations on several "
         "ranks, a larger factor and one more exchange per CG iteration); 2 to 4, also the rows "
         "those ghosts couple to, level by level (Ifpack2's overlap level)",
         rcp(new Teuchos::EnhancedNumberValidator<int>(0, BlockCholmod::kMaxOverlap)));
  cg.set("block reuse", true,
         "BLOCK_CHOLMOD: keep a rank's factor across the Newton iterations of a time step and "
         "refactorise only when the CG iterations the stale factor has cost since its "
         "factorisation (against the rate right after it) outweigh one factorisation; false: "
         "factorise at every solve");
  Teuchos::setStringToIntegralParameter<int>(
      "block precision", "single",
      "BLOCK_CHOLMOD: single, apply each rank's factor from a float copy in double arithmetic "
      "(solver/single_factor.hpp; half the bytes per triangular solve, the same CG tolerance); "
      "double: CHOLMOD's own solve. The copy is made once a factor has served a few applies, so "
      "with 'block reuse: false' (a factorisation per solve) there is none",
      Teuchos::tuple<std::string>("single", "double"), &cg);
  auto& ifp = cg.sublist("Ifpack2", false,
                         "parameters passed to the Ifpack2 preconditioner (checked by bfemp)");
  ifp.disableRecursiveValidation();
  auto& mu = cg.sublist("MueLu", false,
                        "parameters passed to MueLu (checked by MueLu before the first step); "
                        "bfemp's defaults: 'verbosity' none, 'multigrid algorithm' unsmoothed, "
                        "'reuse: type' RP; on > 1 rank 'coarse: type' RELAXATION (4 symmetric "
                        "Gauss-Seidel sweeps: KLU2, MueLu's default, is wrong on several ranks in "
                        "Trilinos 13.2)");
  mu.disableRecursiveValidation();
  return pl;
}

LinearSolverKind linear_solver_kind(const ParameterList& resolved) {
  const std::string t = resolved.get<std::string>("type");
  if (t == "Cholmod") return LinearSolverKind::Cholmod;
  if (t == "KLU2") return LinearSolverKind::KLU2;
  return LinearSolverKind::CG;
}

const char* linear_solver_name(LinearSolverKind kind) {
  switch (kind) {
    case LinearSolverKind::Cholmod: return "Cholmod";
    case LinearSolverKind::KLU2: return "KLU2";
    default: return "CG";
  }
}

struct LinearSolver::Impl {
  using Direct = Amesos2::Solver<Matrix, MultiVec>;
  using Prec = Ifpack2::Preconditioner<double, LO, GO, Node>;
  RCP<const Comm> comm;
  RCP<const Matrix> A;
  RCP<Direct> direct;                      // KLU2 (Amesos2)
  std::unique_ptr<CholmodDirect> cholmod;  // Cholmod: SuiteSparse directly
  bool symbolic_done = false;
  RCP<Prec> prec;
  std::unique_ptr<MueLuPreconditioner> muelu;
  RCP<BlockCholmod> block;  // BLOCK_CHOLMOD: per graph
  std::string prec_name;
  ParameterList ifpack2;
  // SCHWARZ with an AMESOS2 subdomain solve: Ifpack2 13.2's Amesos2 wrapper
  // copies the local matrix's values in initialize(), not in compute(), so
  // compute() alone would factor the values of set_matrix time (zeros, or an
  // earlier Newton iteration's). Such a preconditioner is re-initialised
  // (local copy and symbolic analysis) before every compute().
  bool reinitialise_each_compute = false;
  double cg_tol = 1e-12;
  bool adaptive = true;
  int cg_max_iters = 2000;
  int muelu_rebuild_every = 10;
  int block_overlap = 1;
  bool block_single = true;
  // BLOCK_CHOLMOD factor reuse: whether the factor holds A's values of some
  // earlier solve of this graph and step, a factorisation's cost in CG
  // iterations (flop counts, the costliest rank's), the CG iterations per
  // decade of residual reduction right after it, and the extra iterations the
  // stale factor has cost since. Counts, not timings: a run decides alike
  // every time.
  bool block_reuse = true;
  bool block_valid = false;
  bool block_retrying = false;  // solve() is redoing a stale-factor failure on a fresh factor
  double block_fact_its = 0, block_fresh_rate = 0, block_excess_its = 0;
  CholmodDirect::Reuse reuse;
  RCP<Vector> residual;  // direct solves: the residual check, kept across solves
};

LinearSolver::LinearSolver(const ParameterList& params, const RCP<const Comm>& comm)
    : kind_(linear_solver_kind(params)), impl_(new Impl) {
  impl_->comm = comm;
  if (kind_ != LinearSolverKind::CG && comm->getSize() > 1) {
    std::ostringstream msg;
    msg << "scene key 'Linear Solver/type' = '" << linear_solver_name(kind_)
        << "': direct solvers run on 1 MPI rank only in this Trilinos (13.2: KLU2 gives "
           "wrong answers and Cholmod throws on more ranks); this run has "
        << comm->getSize() << " ranks. Expected 'CG' under MPI.";
    throw std::invalid_argument(msg.str());
  }
  impl_->reuse.max_iterations = kCholmodReuseIterations;
  impl_->reuse.by_cost = true;  // the schema's default
  if (params.isSublist("Cholmod")) {  // a list without it (built by hand) takes the defaults
    const ParameterList& ch = params.sublist("Cholmod");
    if (ch.isParameter("reuse iterations")) impl_->reuse.max_iterations = ch.get<int>("reuse iterations");
    if (ch.isParameter("reuse tolerance")) impl_->reuse.tolerance = ch.get<double>("reuse tolerance");
    if (ch.isParameter("reuse by cost")) impl_->reuse.by_cost = ch.get<bool>("reuse by cost");
    if (ch.isParameter("forcing term")) impl_->reuse.adaptive = ch.get<std::string>("forcing term") == "adaptive";
    if (ch.isParameter("reuse precision")) impl_->reuse.single = ch.get<std::string>("reuse precision") == "single";
  }
  // Cholmod keys away from their defaults would be ignored by another solver: refuse them.
  const CholmodDirect::Reuse defaults;
  const bool ch_set = impl_->reuse.max_iterations != kCholmodReuseIterations ||
                      impl_->reuse.tolerance != defaults.tolerance || !impl_->reuse.by_cost ||
                      impl_->reuse.adaptive != defaults.adaptive || impl_->reuse.single != defaults.single;
  if (kind_ != LinearSolverKind::Cholmod && ch_set)
    throw std::invalid_argument("scene sublist 'Linear Solver/Cholmod' is set but 'Linear Solver/type' is " +
                                std::string(linear_solver_name(kind_)) + ": expected type Cholmod for it, or no such sublist");
  const ParameterList& cg = params.sublist("CG");
  impl_->cg_tol = cg.get<double>("tolerance");
  impl_->adaptive = cg.get<std::string>("forcing term") == "adaptive";
  impl_->cg_max_iters = cg.get<int>("max iterations");
  impl_->muelu_rebuild_every = cg.get<int>("MueLu rebuild every");
  impl_->prec_name = cg.get<std::string>("preconditioner");
  if (cg.isParameter("block overlap")) impl_->block_overlap = cg.get<int>("block overlap");
  if (cg.isParameter("block reuse")) impl_->block_reuse = cg.get<bool>("block reuse");
  if (cg.isParameter("block precision")) impl_->block_single = cg.get<std::string>("block precision") == "single";
  // BLOCK_CHOLMOD keys away from their defaults would be ignored by another preconditioner: refuse them.
  if (kind_ == LinearSolverKind::CG && impl_->prec_name != "BLOCK_CHOLMOD" &&
      (impl_->block_overlap != 1 || !impl_->block_reuse || !impl_->block_single))
    throw std::invalid_argument(std::string("scene key 'Linear Solver/CG/") +
                                (impl_->block_overlap != 1 ? "block overlap' = " + std::to_string(impl_->block_overlap)
                                 : !impl_->block_reuse     ? std::string("block reuse' = false")
                                                           : std::string("block precision' = double")) +
                                " but 'Linear Solver/CG/preconditioner' is " + impl_->prec_name +
                                ": expected BLOCK_CHOLMOD for it, or the key left at its default");
  impl_->ifpack2 = cg.sublist("Ifpack2");
  if (impl_->prec_name == "SCHWARZ" && !impl_->ifpack2.isParameter("schwarz: combine mode"))
    impl_->ifpack2.set("schwarz: combine mode", "ADD");  // 13.2 default (ZERO) is non-symmetric
  impl_->reinitialise_each_compute =
      impl_->prec_name == "SCHWARZ" && impl_->ifpack2.isParameter("schwarz: inner preconditioner name") &&
      impl_->ifpack2.get<std::string>("schwarz: inner preconditioner name") == "AMESOS2";
  if (kind_ == LinearSolverKind::CG) {
    // Parameters for a preconditioner that is not the chosen one would be
    // ignored: refuse them.
    const bool mu = impl_->prec_name == "MUELU";
    const ParameterList& other = mu ? cg.sublist("Ifpack2") : cg.sublist("MueLu");
    if (other.numParams() > 0)
      throw std::invalid_argument(std::string("scene sublist 'Linear Solver/CG/") + (mu ? "Ifpack2" : "MueLu") +
                                  "' has keys ('" + other.name(other.begin()) + "', ...) but 'Linear Solver/CG/"
                                  "preconditioner' is " + impl_->prec_name + ": expected " +
                                  (mu ? "an Ifpack2 preconditioner (RELAXATION, CHEBYSHEV, RILUK, SCHWARZ)"
                                      : "MUELU") + " for them, or no such sublist");
  }
  if (kind_ == LinearSolverKind::CG && impl_->prec_name == "MUELU")
    impl_->muelu = std::make_unique<MueLuPreconditioner>(cg.sublist("MueLu"), comm);
  else if (kind_ == LinearSolverKind::CG)
    check_ifpack2_keys(impl_->prec_name, impl_->ifpack2);
}

bool LinearSolver::detects_indefinite() const {
  return kind_ == LinearSolverKind::Cholmod || (kind_ == LinearSolverKind::CG && impl_->prec_name == "BLOCK_CHOLMOD");
}

bool LinearSolver::wants_near_null_space() const { return impl_->muelu != nullptr; }

int LinearSolver::near_null_space_every() const { return impl_->muelu_rebuild_every; }

void LinearSolver::set_near_null_space(const RCP<MultiVec>& modes, int block_size) {
  if (impl_->muelu) impl_->muelu->set_near_null_space(modes, block_size);
}

int LinearSolver::preconditioner_setups() const {
  if (impl_->muelu) return impl_->muelu->setups();
  return 0;
}

LinearSolver::~LinearSolver() = default;

double LinearSolver::tightest_tolerance() const {
  if (kind_ == LinearSolverKind::Cholmod) return impl_->reuse.tolerance;
  return kind_ == LinearSolverKind::CG ? impl_->cg_tol : 0.0;
}

std::string LinearSolver::describe() const {
  if (kind_ == LinearSolverKind::Cholmod) {
    std::ostringstream s;
    s << "Cholmod (SuiteSparse, symbolic analysis kept per graph";
    if (impl_->reuse.max_iterations > 0)
      s << "; up to " << impl_->reuse.max_iterations
        << (impl_->reuse.by_cost ? " (or one factorisation's cost)" : "") << " CG iterations on the previous factor, tol "
        << impl_->reuse.tolerance << (impl_->reuse.adaptive ? ", adaptive forcing term" : "")
        << (impl_->reuse.single ? ", float copy" : "");
    s << ")";
    return s.str();
  }
  if (kind_ != LinearSolverKind::CG) return std::string("Amesos2 ") + linear_solver_name(kind_);
  std::ostringstream s;
  s << "Belos CG (tol " << impl_->cg_tol << (impl_->adaptive ? ", adaptive forcing term" : "") << ", max "
    << impl_->cg_max_iters << ") + "
    << (impl_->muelu ? impl_->muelu->describe() : "Ifpack2 " + impl_->prec_name);
  return s.str();
}

void LinearSolver::forget_factor() {
  if (impl_->cholmod) impl_->cholmod->forget_factor();
  if (!impl_->block.is_null()) impl_->block->new_step();
  impl_->block_valid = false;
}

void LinearSolver::set_matrix(const RCP<const Matrix>& A) {
  auto& m = *impl_;
  m.A = A;
  if (kind_ == LinearSolverKind::CG) {
    m.prec = Teuchos::null;
    m.block = Teuchos::null;
    if (m.muelu) {
      m.muelu->set_matrix(A);
    } else if (m.prec_name == "BLOCK_CHOLMOD") {
      m.block = rcp(new BlockCholmod(A, m.block_overlap, m.block_single));
      m.block_valid = false;
    } else if (m.prec_name != "NONE") {
      m.prec = Ifpack2::Factory::create<Tpetra::RowMatrix<double, LO, GO, Node>>(m.prec_name, A);
      try {
        m.prec->setParameters(m.ifpack2);
      } catch (const std::exception& e) {
        throw std::invalid_argument("scene sublist 'Linear Solver/CG/Ifpack2' rejected by " +
                                    m.prec_name + ": " + e.what());
      }
      if (!m.reinitialise_each_compute) m.prec->initialize();  // else at each compute (see Impl)
    }
    return;
  }
  if (kind_ == LinearSolverKind::Cholmod) {
    if (!m.cholmod) m.cholmod = std::make_unique<CholmodDirect>(m.reuse);
    m.cholmod->set_matrix(A);
    return;
  }
  const std::string name = linear_solver_name(kind_);
  m.direct = Amesos2::create<Matrix, MultiVec>(name, A);
  auto p = Teuchos::parameterList("Amesos2");
  p->sublist(name);  // Cholmod must see setParameters before its first factorisation
  m.direct->setParameters(p);
  m.symbolic_done = false;
}

LinearSolveStats LinearSolver::solve(const Vector& b, Vector& x, double forcing, bool from_x) {
  auto& m = *impl_;
  if (m.A.is_null()) throw std::logic_error("LinearSolver::solve before set_matrix");
  LinearSolveStats stats;
  if (kind_ != LinearSolverKind::CG) {
    try {
      if (m.cholmod) {
        // 'forcing term: adaptive': CG on the previous factor stops at the
        // Newton forcing term (floor: the reuse tolerance); a factorisation's
        // solve is exact either way.
        const double ctol = m.reuse.adaptive && forcing > 0 ? std::min(0.1, forcing) : 0.0;
        const CholmodDirect::Result r = m.cholmod->solve(b, x, ctol, from_x);
        stats.tolerance = r.tolerance;
        stats.refactored = r.analysed;
        stats.factorised = r.factorised;
        stats.iterations = r.cg_iterations + (r.factorised ? 1 : 0);
        stats.factor_s = r.factor_s;
        stats.reuse_cg_s = r.cg_s;
        stats.reuse_cg_iterations = r.cg_iterations;
      } else {
        stats.factorised = true;
        stats.iterations = 1;
        if (!m.symbolic_done) {
          m.direct->symbolicFactorization();
          m.symbolic_done = true;
          stats.refactored = true;
        }
        m.direct->numericFactorization();
        m.direct->solve(Teuchos::ptr(static_cast<MultiVec*>(&x)),
                        Teuchos::ptr(static_cast<const MultiVec*>(&b)));
      }
    } catch (const SolverError&) {
      throw;
    } catch (const std::exception& e) {
      throw SolverError(std::string(linear_solver_name(kind_)) + " factorisation/solve failed: " +
                        e.what());
    }
    // One residual check per solve: a direct solver that silently returns a
    // wrong answer is a failure. (Cholmod's CG on the previous factor stopped
    // at `tolerance` by its recursive residual, which matches the true one to
    // round-off: 2x leaves room for that and nothing more.)
    if (m.residual.is_null() || !m.residual->getMap()->isSameAs(*b.getMap()))
      m.residual = rcp(new Vector(b.getMap()));
    Vector& r = *m.residual;
    m.A->apply(x, r);
    r.update(1.0, b, -1.0);
    const double bn = b.norm2();
    stats.achieved_tol = bn > 0 ? r.norm2() / bn : r.norm2();
    if (!(stats.achieved_tol < std::max(1e-6, 2.0 * stats.tolerance)))
      throw SolverError(std::string(linear_solver_name(kind_)) +
                        " solve is inaccurate: relative residual " +
                        std::to_string(stats.achieved_tol));
    return stats;
  }
  RCP<Operator> M;
  if (m.muelu) {
    try {
      m.muelu->compute();
    } catch (const std::exception& e) {
      throw SolverError(std::string("MueLu set-up failed: ") + e.what());
    }
    M = m.muelu->op();
  } else if (!m.block.is_null()) {
    // Ski rental: refactorise once the extra CG iterations on the stale
    // factor have cost as much as a factorisation. A factorisation's flops
    // are priced kBlas3Advantage times cheaper than a CG iteration's (dense
    // BLAS 3 against memory-bound triangular solves) when every rank's
    // factor is supernodal, as Cholmod's reuse budget does for a supernodal
    // factor (cholmod_direct.hpp; a simplicial one has no BLAS 3). Paper twist, 2 ranks x 1 thread:
    // without that factor 2.4 factorisations and 668 CG iterations per step,
    // 11.7 s of solve; with it 3.4 and 482, 10.6 s (perf/README).
    const bool fresh = !m.block_reuse || !m.block_valid || m.block_excess_its >= m.block_fact_its;
    if (fresh) {
      m.block_valid = false;
      const double before = m.block->local_factor_seconds();
      m.block->compute();  // throws NotPositiveDefinite on every rank if a block is indefinite
      stats.factor_s = m.block->local_factor_seconds() - before;
      {  // the costliest rank's factorisation, in its CG iterations (every rank decides alike)
        const double mine[3] = {m.block->factor_flops(), m.block->iteration_flops(),
                                m.block->supernodal() ? 0.0 : 1.0};
        double most[3] = {0, 0, 0};
        Teuchos::reduceAll(*m.comm, Teuchos::REDUCE_MAX, 3, mine, most);
        const double price = most[2] == 0.0 ? CholmodReuse::kBlas3Advantage : 1.0;
        m.block_fact_its = most[1] > 0 ? most[0] / (price * most[1]) : 0.0;
      }
      m.block_valid = true;
      m.block_excess_its = 0;
      stats.factorised = true;
    }
    m.block->prepare_solve();  // the float copy, once the factor has served enough applies
    M = m.block;
  } else if (!m.prec.is_null()) {
    if (m.reinitialise_each_compute) m.prec->initialize();
    m.prec->compute();
    M = m.prec;
  }
  const double tol = m.adaptive && forcing > 0 ? std::max(m.cg_tol, std::min(0.1, forcing)) : m.cg_tol;
  stats.tolerance = tol;
  // CG from x (from_x), else from 0; a start worse than 0 (|b - A x| > |b|)
  // from 0. The block factor's rate below counts decades from the start's
  // relative residual.
  double start_rel = 1.0;
  if (from_x) {
    if (m.residual.is_null() || !m.residual->getMap()->isSameAs(*b.getMap())) m.residual = rcp(new Vector(b.getMap()));
    m.A->apply(x, *m.residual);
    m.residual->update(1.0, b, -1.0);
    const double bn = b.norm2();
    start_rel = bn > 0 ? m.residual->norm2() / bn : 1.0;
  }
  if (!(start_rel < 1.0)) {
    x.putScalar(0.0);
    start_rel = 1.0;
  }
  auto bp = Teuchos::parameterList();
  bp->set("Convergence Tolerance", tol);
  bp->set("Maximum Iterations", m.cg_max_iters);
  bp->set("Implicit Residual Scaling", "Norm of RHS");
  bp->set("Explicit Residual Scaling", "Norm of RHS");
  bp->set("Verbosity", Belos::Errors);
  auto xp = Teuchos::rcpFromRef(static_cast<MultiVec&>(x));
  auto bpv = Teuchos::rcpFromRef(static_cast<const MultiVec&>(b));
  auto problem = rcp(new Belos::LinearProblem<double, MultiVec, Operator>(m.A, xp, bpv));
  if (!M.is_null()) problem->setLeftPrec(M);
  problem->setProblem();
  Belos::PseudoBlockCGSolMgr<double, MultiVec, Operator> cg(problem, bp);
  Belos::ReturnType ret;
  try {
    ret = cg.solve();
  } catch (const std::exception& e) {
    // Belos' CGIterateFailure is p^T A p <= 0 for a direction p != 0: with
    // an SPD preconditioner (the block Cholesky factors) this proves A is
    // not positive definite.
    if (!m.block.is_null() && dynamic_cast<const Belos::CGIterateFailure*>(&e))
      throw NotPositiveDefinite(std::string("CG met p^T A p <= 0 under BLOCK_CHOLMOD: the matrix is not positive "
                                            "definite (") + e.what() + ")");
    throw SolverError(std::string("CG failed (matrix not positive definite?): ") + e.what());
  }
  stats.iterations = cg.getNumIters();
  stats.achieved_tol = cg.achievedTol();
  if (!m.block.is_null() && m.block_reuse && ret == Belos::Converged && stats.iterations > 0 && !m.block_retrying) {
    // CG iterations per decade of residual reduction, fresh factor against stale
    const double decades = std::max(1.0, std::log10(start_rel / std::max(stats.achieved_tol, 1e-300)));
    const double rate = stats.iterations / decades;
    if (stats.factorised) m.block_fresh_rate = rate;
    else m.block_excess_its += std::max(0.0, (rate - m.block_fresh_rate) * decades);
  }
  if (ret != Belos::Converged && !m.block.is_null() && !stats.factorised) {
    // The stale factor was not good enough for these values: refactorise and
    // solve again from CG's last iterate (a failure then is the solver's).
    // (Its rate, from CG's last iterate, is not a fresh factor's rate from zero.)
    m.block_valid = false;
    m.block_retrying = true;
    LinearSolveStats again;
    try {
      again = solve(b, x, forcing, true);
    } catch (...) {
      m.block_retrying = false;
      throw;
    }
    m.block_retrying = false;
    again.iterations += stats.iterations;
    again.stale_retries += 1;
    return again;
  }
  if (ret != Belos::Converged) {
    std::ostringstream msg;
    msg << "CG did not converge: " << stats.iterations << " iterations, relative residual "
        << stats.achieved_tol << " > tolerance " << tol
        << " (raise 'Linear Solver/CG/max iterations' or choose a stronger preconditioner)";
    throw SolverError(msg.str());
  }
  return stats;
}

}  // namespace bfemp
