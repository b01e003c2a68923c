#pragma once
// Material points of all MPM bodies as a structure of arrays on Kokkos Views:
// one entry per particle in each View, the same index across Views. Plain
// data; kernels capture the Views they need.
#include <Kokkos_Core.hpp>
#include <cstddef>
#include <vector>

#include "core/types.hpp"

namespace bfemp {

template <int dim>
struct Particles {
  Kokkos::View<double* [dim], MemSpace> x;            // current position
  Kokkos::View<double* [dim], MemSpace> v;            // velocity
  Kokkos::View<double*, MemSpace> mass;               // constant in time
  Kokkos::View<double*, MemSpace> volume0;            // rest volume; V = J volume0
  Kokkos::View<double* [dim][dim], MemSpace> F;       // deformation gradient
  Kokkos::View<double* [dim][dim], MemSpace> C;       // APIC affine matrix
  Kokkos::View<int*, MemSpace> body;                  // body index in the scene
  Kokkos::View<int*, MemSpace> material;              // material index in the scene

  std::size_t size() const { return mass.extent(0); }
};

// n particles: x, v, mass, volume0, C, body, material zero; F the identity.
template <int dim>
Particles<dim> allocate_particles(std::size_t n) {
  Particles<dim> p;
  p.x = decltype(p.x)("mpm_x", n);
  p.v = decltype(p.v)("mpm_v", n);
  p.mass = decltype(p.mass)("mpm_mass", n);
  p.volume0 = decltype(p.volume0)("mpm_volume0", n);
  p.F = decltype(p.F)("mpm_F", n);
  p.C = decltype(p.C)("mpm_C", n);
  p.body = decltype(p.body)("mpm_body", n);
  p.material = decltype(p.material)("mpm_material", n);
  auto F = p.F;
  Kokkos::parallel_for(
      "mpm_init_F", Kokkos::RangePolicy<ExecSpace>(0, n), KOKKOS_LAMBDA(const std::size_t q) {
        for (int i = 0; i < dim; ++i)
          for (int j = 0; j < dim; ++j) F(q, i, j) = i == j ? 1.0 : 0.0;
      });
  Kokkos::fence();
  return p;
}

// All particles of `parts`, in order (part 0 first). Every field is copied,
// body and material indices unchanged.
// Node-interleaved copy of the particle positions: xp(q dim + c) = x(q, c)
// (xp sized np dim by the caller).
template <int dim>
void interleaved_positions(const Particles<dim>& p, Kokkos::View<double*, MemSpace> xp) {
  auto px = p.x;
  Kokkos::parallel_for(
      "particle_positions_interleaved", Kokkos::RangePolicy<ExecSpace>(0, p.size()), KOKKOS_LAMBDA(const std::size_t q) {
        for (int c = 0; c < dim; ++c) xp(q * dim + c) = px(q, c);
      });
}

template <int dim>
Particles<dim> concatenate(const std::vector<Particles<dim>>& parts) {
  std::size_t n = 0;
  for (const auto& part : parts) n += part.size();
  Particles<dim> out = allocate_particles<dim>(n);
  std::size_t offset = 0;
  for (const auto& part : parts) {
    const Particles<dim> src = part;
    const Particles<dim> dst = out;
    const std::size_t off = offset;
    Kokkos::parallel_for(
        "mpm_concatenate", Kokkos::RangePolicy<ExecSpace>(0, src.size()),
        KOKKOS_LAMBDA(const std::size_t q) {
          const std::size_t t = off + q;
          for (int i = 0; i < dim; ++i) {
            dst.x(t, i) = src.x(q, i);
            dst.v(t, i) = src.v(q, i);
            for (int j = 0; j < dim; ++j) {
              dst.F(t, i, j) = src.F(q, i, j);
              dst.C(t, i, j) = src.C(q, i, j);
            }
          }
          dst.mass(t) = src.mass(q);
          dst.volume0(t) = src.volume0(q);
          dst.body(t) = src.body(q);
          dst.material(t) = src.material(q);
        });
    offset += part.size();
  }
  Kokkos::fence();
  return out;
}

}  // namespace bfemp
