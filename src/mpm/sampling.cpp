#include "mpm/sampling.hpp"

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <limits>
#include <stdexcept>

namespace bfemp {
namespace {

constexpr double kPi = 3.14159265358979323846;
constexpr double kMaxCandidates = 1e8;

std::string fmt(double v) {
  char s[32];
  std::snprintf(s, sizeof s, "%.10g", v);
  return s;
}

[[noreturn]] void bad(const std::string& field, const std::string& value, const std::string& expected) {
  throw std::invalid_argument("sampling field '" + field + "' = " + value + ": expected " + expected);
}

void require_positive(const std::string& field, double v) {
  if (!(v > 0.0) || !std::isfinite(v)) bad(field, fmt(v), "a finite value > 0");
}

// Dimension of a kind: 2, 3, or 0 for kinds available in both.
int kind_dim(const std::string& kind) {
  if (kind == "rectangle" || kind == "disk" || kind == "ring" || kind == "half-ring") return 2;
  if (kind == "sphere") return 3;
  if (kind == "box" || kind == "mesh" || kind == "sdf") return 0;
  bad("kind", "'" + kind + "'", "one of box, rectangle, disk, sphere, ring, half-ring, mesh, sdf");
}

bool is_box(const std::string& kind) { return kind == "box" || kind == "rectangle"; }

// Checks every field the kind uses (and only those).
void validate_shape(const SamplingShape& s, int dim) {
  if (dim != 2 && dim != 3) bad("dim", std::to_string(dim), "2 or 3");
  const int kd = kind_dim(s.kind);
  if (kd != 0 && kd != dim)
    bad("kind", "'" + s.kind + "'",
        "a " + std::to_string(dim) + "D shape (it is " + std::to_string(kd) + "D)");
  if (!s.center.empty() && s.center.size() != static_cast<std::size_t>(dim))
    bad("center", std::to_string(s.center.size()) + " entries", std::to_string(dim) + " entries");
  for (double c : s.center)
    if (!std::isfinite(c)) bad("center", fmt(c), "finite coordinates");
  if (is_box(s.kind) || s.kind == "sdf") {
    if (s.size.size() != static_cast<std::size_t>(dim))
      bad("size", std::to_string(s.size.size()) + " entries", std::to_string(dim) + " entries");
    for (std::size_t i = 0; i < s.size.size(); ++i) require_positive("size[" + std::to_string(i) + "]", s.size[i]);
    if (s.kind == "sdf" && !s.sdf) bad("sdf", "empty", "a signed-distance function");
  } else if (s.kind == "mesh") {
    if (s.mesh == nullptr) bad("mesh", "null", "a mesh");
    if (s.mesh->dim != dim) bad("mesh", "of dimension " + std::to_string(s.mesh->dim), std::to_string(dim) + "D");
    if (s.mesh->num_cells() == 0) bad("mesh", "without cells", "at least one cell");
  } else {
    require_positive("outer_radius", s.outer_radius);
    if (s.kind == "ring" || s.kind == "half-ring") {
      require_positive("inner_radius", s.inner_radius);
      if (s.inner_radius >= s.outer_radius)
        bad("inner_radius", fmt(s.inner_radius), "< outer_radius = " + fmt(s.outer_radius));
    }
  }
}

template <int dim>
Vec<dim> center_of(const SamplingShape& s) {
  Vec<dim> c = Vec<dim>::Zero();
  for (std::size_t d = 0; d < s.center.size(); ++d) c[d] = s.center[d];
  return c;
}

// Axis-aligned box [lo, hi] holding the whole shape.
template <int dim>
void bounding_box(const SamplingShape& s, Vec<dim>& lo, Vec<dim>& hi) {
  const Vec<dim> c = center_of<dim>(s);
  if (is_box(s.kind) || s.kind == "sdf") {
    for (int d = 0; d < dim; ++d) {
      lo[d] = c[d] - 0.5 * s.size[d];
      hi[d] = c[d] + 0.5 * s.size[d];
    }
  } else if (s.kind == "mesh") {
    lo.setConstant(std::numeric_limits<double>::infinity());
    hi = -lo;
    const MeshData& m = *s.mesh;
    for (std::size_t n = 0; n < m.num_nodes(); ++n)
      for (int d = 0; d < dim; ++d) {
        lo[d] = std::min(lo[d], m.coords[n * dim + d]);
        hi[d] = std::max(hi[d], m.coords[n * dim + d]);
      }
  } else {
    lo = (c.array() - s.outer_radius).matrix();
    hi = (c.array() + s.outer_radius).matrix();
    if (s.kind == "half-ring") lo[1] = c[1];
  }
}

// Negative strictly inside an analytic or sdf shape.
template <int dim>
double inside_function(const SamplingShape& s, const Vec<dim>& c, const Vec<dim>& x) {
  if (is_box(s.kind)) return ((x - c).cwiseAbs() - 0.5 * Vec<dim>(s.size.data())).maxCoeff();
  if (s.kind == "sdf") return s.sdf(x.data());
  const double r = (x - c).norm();
  if (s.kind == "disk" || s.kind == "sphere") return r - s.outer_radius;
  const double ring = std::max(r - s.outer_radius, s.inner_radius - r);
  return s.kind == "ring" ? ring : std::max(ring, c[1] - x[1]);
}

// Candidate lattice: points m in [m_lo, m_lo + count) per axis, point
// coordinate (m + 1/2) h, linear index with x fastest.
template <int dim>
struct Lattice {
  long long m_lo[dim], count[dim];
  double h;
  std::size_t size() const {
    std::size_t n = 1;
    for (int d = 0; d < dim; ++d) n *= static_cast<std::size_t>(count[d]);
    return n;
  }
  Vec<dim> point(const long long* m) const {
    Vec<dim> x;
    for (int d = 0; d < dim; ++d) x[d] = (static_cast<double>(m[d]) + 0.5) * h;
    return x;
  }
  std::size_t linear(const long long* m) const {
    std::size_t n = 0;
    for (int d = dim - 1; d >= 0; --d) n = n * count[d] + static_cast<std::size_t>(m[d] - m_lo[d]);
    return n;
  }
};

// Calls f(m) for every m with lo <= m <= hi (inclusive, x fastest).
template <int dim, class Fn>
void for_each_point(const long long* lo, const long long* hi, Fn&& f) {
  for (int d = 0; d < dim; ++d)
    if (hi[d] < lo[d]) return;
  long long m[dim];
  std::copy(lo, lo + dim, m);
  for (;;) {
    f(static_cast<const long long*>(m));
    int d = 0;
    for (; d < dim && m[d] == hi[d]; ++d) m[d] = lo[d];  // carry into the next axis
    if (d == dim) return;
    ++m[d];
  }
}

// Lattice points inside the cells of the mesh (barycentric test with a
// rounding tolerance, so points on shared faces are never lost).
template <int dim>
std::vector<char> mesh_marks(const MeshData& mesh, const Lattice<dim>& L) {
  std::vector<char> mark(L.size(), 0);
  constexpr double tol = 1e-12;
  for (std::size_t c = 0; c < mesh.num_cells(); ++c) {
    const long long* v = &mesh.cells[c * (dim + 1)];
    const Vec<dim> X0(&mesh.coords[v[0] * dim]);
    Mat<dim> T;
    Vec<dim> lo = X0, hi = X0;
    for (int k = 1; k <= dim; ++k) {
      const Vec<dim> Xk(&mesh.coords[v[k] * dim]);
      T.col(k - 1) = Xk - X0;
      lo = lo.cwiseMin(Xk);
      hi = hi.cwiseMax(Xk);
    }
    const Mat<dim> Tinv = T.inverse();
    long long mlo[dim], mhi[dim];
    for (int d = 0; d < dim; ++d) {
      mlo[d] = std::max(L.m_lo[d], static_cast<long long>(std::ceil(lo[d] / L.h - 0.5)) - 1);
      mhi[d] = std::min(L.m_lo[d] + L.count[d] - 1, static_cast<long long>(std::floor(hi[d] / L.h - 0.5)) + 1);
    }
    for_each_point<dim>(mlo, mhi, [&](const long long* m) {
      const Vec<dim> lam = Tinv * (L.point(m) - X0);
      if (lam.minCoeff() >= -tol && lam.sum() <= 1.0 + tol) mark[L.linear(m)] = 1;
    });
  }
  return mark;
}

}  // namespace

double sampling_shape_measure(const SamplingShape& s, int dim) {
  validate_shape(s, dim);
  if (is_box(s.kind)) {
    double v = 1.0;
    for (double e : s.size) v *= e;
    return v;
  }
  if (s.kind == "mesh") return total_measure(*s.mesh);
  if (s.kind == "sdf") return std::numeric_limits<double>::quiet_NaN();
  const double R = s.outer_radius, r = s.inner_radius;
  if (s.kind == "disk") return kPi * R * R;
  if (s.kind == "sphere") return 4.0 / 3.0 * kPi * R * R * R;
  return (s.kind == "ring" ? 1.0 : 0.5) * kPi * (R * R - r * r);
}

namespace {

// A validated shape on its candidate lattice (sub-cell centres of the cells
// its bounding box touches), with the inside test of every lattice point.
template <int dim>
struct ShapeLattice {
  const SamplingShape* shape = nullptr;
  Lattice<dim> L;
  std::vector<char> mark;  // kind "mesh": inside flags by L.linear
  Vec<dim> c;
  bool inside(const long long* m) const {
    return shape->kind == "mesh" ? mark[L.linear(m)] != 0 : inside_function<dim>(*shape, c, L.point(m)) < 0.0;
  }
  void last(long long* hi) const {
    for (int d = 0; d < dim; ++d) hi[d] = L.m_lo[d] + L.count[d] - 1;
  }
};

// Points per axis and cell for ppc (throws for a ppc not available in dim).
template <int dim>
int points_per_axis(int ppc) {
  for (int k = 1; k <= (dim == 2 ? 4 : 3); ++k)
    if (static_cast<int>(std::pow(k, dim) + 0.5) == ppc) return k;
  bad("ppc", std::to_string(ppc), dim == 2 ? "one of 1, 4, 9, 16 in 2D" : "one of 1, 8, 27 in 3D");
}

// with_marks false: a mesh shape's inside flags are left for add_marks (a
// lattice only compared by its range).
template <int dim>
ShapeLattice<dim> shape_lattice(const SamplingShape& shape, double dx, int ppc, bool with_marks = true) {
  validate_shape(shape, dim);
  require_positive("dx", dx);
  const int s = points_per_axis<dim>(ppc);
  Vec<dim> lo, hi;
  bounding_box<dim>(shape, lo, hi);
  ShapeLattice<dim> S;
  S.shape = &shape;
  S.L.h = dx / s;
  double candidates = 1.0;
  for (int d = 0; d < dim; ++d) {
    const double c_lo = std::floor(lo[d] / dx), c_hi = std::ceil(hi[d] / dx);
    candidates *= std::max(1.0, c_hi - c_lo) * s;
    if (!(candidates <= kMaxCandidates))  // also catches huge coordinates / dx
      bad("dx", fmt(dx), "a larger value (the shape '" + shape.kind + "' would need more than " +
                             fmt(kMaxCandidates) + " candidate points)");
    S.L.m_lo[d] = static_cast<long long>(c_lo) * s;
    S.L.count[d] = static_cast<long long>(std::max(1.0, c_hi - c_lo)) * s;
  }
  if (shape.kind == "mesh" && with_marks) S.mark = mesh_marks<dim>(*shape.mesh, S.L);
  S.c = center_of<dim>(shape);
  return S;
}

template <int dim>
void add_marks(ShapeLattice<dim>& S) {
  if (S.shape->kind == "mesh" && S.mark.empty()) S.mark = mesh_marks<dim>(*S.shape->mesh, S.L);
}

// The first lattice point inside both (x fastest over the intersection of
// their ranges); false when there is none.
template <int dim>
bool first_shared(ShapeLattice<dim>& A, ShapeLattice<dim>& B, double* x) {
  long long lo[dim], hi[dim], ha[dim], hb[dim];
  A.last(ha);
  B.last(hb);
  for (int d = 0; d < dim; ++d) {
    lo[d] = std::max(A.L.m_lo[d], B.L.m_lo[d]);
    hi[d] = std::min(ha[d], hb[d]);
    if (hi[d] < lo[d]) return false;  // the ranges do not meet (no marks needed)
  }
  add_marks(A);
  add_marks(B);
  bool found = false;
  long long at[dim];
  for_each_point<dim>(lo, hi, [&](const long long* m) {
    if (found || !A.inside(m) || !B.inside(m)) return;
    found = true;
    std::copy(m, m + dim, at);
  });
  if (found) {
    const Vec<dim> p = A.L.point(at);
    for (int d = 0; d < dim; ++d) x[d] = p[d];
  }
  return found;
}

// Calls keep(k, x) for the inside points k = 0, 1, ... (x fastest) and
// returns their number; throws for a shape that holds none.
template <int dim, class Fn>
long long scan_inside(const ShapeLattice<dim>& S, double dx, int ppc, Fn&& keep) {
  long long k = 0, last[dim];
  S.last(last);
  for_each_point<dim>(S.L.m_lo, last, [&](const long long* m) {
    if (S.inside(m)) keep(k++, S.L.point(m));
  });
  if (k == 0)
    throw std::invalid_argument("shape '" + S.shape->kind + "' with dx " + fmt(dx) +
                                " produced no particles (ppc " + std::to_string(ppc) +
                                "): expected the shape to contain at least one sub-cell centre; "
                                "use a smaller dx or a larger ppc");
  return k;
}

}  // namespace

template <int dim>
long long count_particles(const SamplingShape& shape, double dx, int ppc) {
  return scan_inside(shape_lattice<dim>(shape, dx, ppc), dx, ppc, [](long long, const Vec<dim>&) {});
}

template <int dim>
Particles<dim> sample_particles(const SamplingShape& shape, double dx, int ppc, double density,
                                int body_id, int material_id) {
  return sample_particles<dim>(shape, dx, ppc, density, body_id, material_id, 0, -1);
}

template <int dim>
Particles<dim> sample_particles(const SamplingShape& shape, double dx, int ppc, double density, int body_id,
                                int material_id, long long first, long long count) {
  validate_shape(shape, dim);  // (the checks in their order before the work of the lattice)
  require_positive("dx", dx);
  require_positive("density", density);
  points_per_axis<dim>(ppc);
  if (body_id < 0) bad("body_id", std::to_string(body_id), ">= 0");
  if (material_id < 0) bad("material_id", std::to_string(material_id), ">= 0");
  if (first < 0) bad("first", std::to_string(first), ">= 0");
  const ShapeLattice<dim> S = shape_lattice<dim>(shape, dx, ppc);
  const long long end = count < 0 ? std::numeric_limits<long long>::max() : first + count;
  std::vector<Vec<dim>> kept;
  const long long total = scan_inside(S, dx, ppc, [&](long long k, const Vec<dim>& x) {
    if (k >= first && k < end) kept.push_back(x);
  });
  if (first > total || (count >= 0 && end > total))
    bad("first", std::to_string(first), "a range of " + std::to_string(count) + " particles inside the shape's " +
                                             std::to_string(total));

  Particles<dim> p = allocate_particles<dim>(kept.size());
  auto x = Kokkos::create_mirror_view(p.x);
  auto mass = Kokkos::create_mirror_view(p.mass);
  auto vol = Kokkos::create_mirror_view(p.volume0);
  auto body = Kokkos::create_mirror_view(p.body);
  auto mat = Kokkos::create_mirror_view(p.material);
  const double v0 = std::pow(dx, dim) / ppc;
  for (std::size_t q = 0; q < kept.size(); ++q) {
    for (int d = 0; d < dim; ++d) x(q, d) = kept[q][d];
    vol(q) = v0;
    mass(q) = density * v0;
    body(q) = body_id;
    mat(q) = material_id;
  }
  Kokkos::deep_copy(p.x, x);
  Kokkos::deep_copy(p.mass, mass);
  Kokkos::deep_copy(p.volume0, vol);
  Kokkos::deep_copy(p.body, body);
  Kokkos::deep_copy(p.material, mat);
  return p;
}

template <int dim>
bool first_shared_point(const SamplingShape& a, const SamplingShape& b, double dx, int ppc, double* x) {
  ShapeLattice<dim> A = shape_lattice<dim>(a, dx, ppc, false), B = shape_lattice<dim>(b, dx, ppc, false);
  return first_shared(A, B, x);
}

template <int dim>
bool first_overlapping_pair(const std::vector<SamplingShape>& shapes, double dx, int ppc, int& a, int& b, double* x) {
  std::vector<ShapeLattice<dim>> S;
  S.reserve(shapes.size());
  for (const SamplingShape& s : shapes) S.push_back(shape_lattice<dim>(s, dx, ppc, false));
  for (a = 0; a < static_cast<int>(S.size()); ++a)
    for (b = a + 1; b < static_cast<int>(S.size()); ++b)
      if (first_shared(S[a], S[b], x)) return true;
  return false;
}

template <int dim>
std::string sampling_report(const SamplingShape& shape, const Particles<dim>& particles, double dx,
                            int ppc) {
  auto mass = particles.mass;
  auto vol = particles.volume0;
  double total_mass = 0.0, total_volume = 0.0;
  Kokkos::parallel_reduce(
      "mpm_sampling_mass", Kokkos::RangePolicy<ExecSpace>(0, particles.size()),
      KOKKOS_LAMBDA(const std::size_t q, double& acc) { acc += mass(q); }, total_mass);
  Kokkos::parallel_reduce(
      "mpm_sampling_volume", Kokkos::RangePolicy<ExecSpace>(0, particles.size()),
      KOKKOS_LAMBDA(const std::size_t q, double& acc) { acc += vol(q); }, total_volume);
  std::string line = "shape '" + shape.kind + "': " + std::to_string(particles.size()) +
                     " particles (dx " + fmt(dx) + ", ppc " + std::to_string(ppc) + "), volume " +
                     fmt(total_volume);
  if (shape.kind != "sdf") {
    const double exact = sampling_shape_measure(shape, dim);
    char rel[32];
    std::snprintf(rel, sizeof rel, "%+.2f%%", 100.0 * (total_volume / exact - 1.0));
    line += " (shape " + fmt(exact) + ", " + rel + ")";
  }
  return line + ", mass " + fmt(total_mass);
}

template Particles<2> sample_particles<2>(const SamplingShape&, double, int, double, int, int);
template Particles<3> sample_particles<3>(const SamplingShape&, double, int, double, int, int);
template Particles<2> sample_particles<2>(const SamplingShape&, double, int, double, int, int, long long, long long);
template Particles<3> sample_particles<3>(const SamplingShape&, double, int, double, int, int, long long, long long);
template long long count_particles<2>(const SamplingShape&, double, int);
template long long count_particles<3>(const SamplingShape&, double, int);
template bool first_shared_point<2>(const SamplingShape&, const SamplingShape&, double, int, double*);
template bool first_shared_point<3>(const SamplingShape&, const SamplingShape&, double, int, double*);
template bool first_overlapping_pair<2>(const std::vector<SamplingShape>&, double, int, int&, int&, double*);
template bool first_overlapping_pair<3>(const std::vector<SamplingShape>&, double, int, int&, int&, double*);
template std::string sampling_report<2>(const SamplingShape&, const Particles<2>&, double, int);
template std::string sampling_report<3>(const SamplingShape&, const Particles<3>&, double, int);

}  // namespace bfemp
