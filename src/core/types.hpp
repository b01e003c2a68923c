#pragma once
// Type aliases shared by the whole solver: Tpetra's instantiated ordinals and
// node, Kokkos spaces, and small fixed-size Eigen types for local algebra.
#include <Eigen/Dense>
#include <Kokkos_Core.hpp>
#include <Tpetra_Map_decl.hpp>

namespace bfemp {

using Map = Tpetra::Map<>;
using LO = Map::local_ordinal_type;   // int
using GO = Map::global_ordinal_type;  // long long (the only instantiated GO)
using Node = Map::node_type;          // Kokkos::Compat::KokkosOpenMPWrapperNode
using ExecSpace = Node::execution_space;
using MemSpace = Node::memory_space;

// Small dense algebra inside kernels goes through these aliases so that a
// device backend can swap them later.
template <int dim>
using Vec = Eigen::Matrix<double, dim, 1>;
template <int dim>
using Mat = Eigen::Matrix<double, dim, dim>;
template <int n>
using SquareMat = Eigen::Matrix<double, n, n>;
// dP/dF as a (dim*dim) x (dim*dim) matrix acting on column-major vec(F):
// entry (i + dim*j, k + dim*l) = d P_ij / d F_kl.
template <int dim>
using StressDerivative = Eigen::Matrix<double, dim * dim, dim * dim>;

}  // namespace bfemp
