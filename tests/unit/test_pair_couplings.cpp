// The contact pairs' graph couplings (contact/pair_couplings.hpp), declared
// once per run of pairs whose particles share a stencil, against every
// pair's couplings declared on the host: each particle's stencil block, the
// stencil with the primitive's vertices (both ways), the vertices among
// themselves, and every diagonal; nothing more. Pairs sorted by particle,
// particles drawn from a few stencils (runs across particles), stencil nodes
// < 0 (skipped), primitives with fewer vertices than slots, and no pairs.
#include <gtest/gtest.h>

#include <algorithm>
#include <random>
#include <set>
#include <tuple>
#include <utility>
#include <vector>

#include "contact/pair_couplings.hpp"
#include "kernels/node_graph.hpp"

using namespace bfemp;

namespace {

static_assert(Kokkos::SpaceAccessibility<Kokkos::HostSpace, MemSpace>::accessible,
              "the test fills and reads the views on the host");

using Pairs = std::set<std::pair<LO, LO>>;

Pairs built_graph(LO n_nodes, const Kokkos::View<LO*, MemSpace>& q, const Kokkos::View<LO*, MemSpace>& j,
                  const Kokkos::View<LO**, MemSpace>& pn, const Kokkos::View<LO**, MemSpace>& vn,
                  const Kokkos::View<int*, MemSpace>& vc) {
  NodeGraphBuilder g(n_nodes);
  const long n = static_cast<long>(q.extent(0));
  const auto q_of = KOKKOS_LAMBDA(const long k) { return q(k); };
  const auto j_of = KOKKOS_LAMBDA(const long k) { return j(k); };
  add_pair_couplings(g, n, q_of, j_of, pn, vn, vc);
  g.start_fill();
  add_pair_couplings(g, n, q_of, j_of, pn, vn, vc);
  NodeGraphBuilder::RowMap rows;
  NodeGraphBuilder::Entries cols;
  g.finish(rows, cols);
  Pairs out;
  for (LO r = 0; r < n_nodes; ++r) {
    for (std::size_t k = rows(r); k < rows(r + 1); ++k) {
      EXPECT_TRUE(k == rows(r) || cols(k - 1) < cols(k)) << "row " << r << " sorted, no repeats";
      out.emplace(r, cols(k));
    }
  }
  return out;
}

void check(int ns, int nv, long n_pairs, unsigned seed) {
  std::mt19937 rng(seed);
  const LO n_nodes = 300;
  const LO n_particles = 80, n_prims = 50, n_stencils = 7;
  // A few stencils (some nodes < 0), each particle one of them. Node
  // n_nodes - 1 is in no stencil and no primitive: the vertex slots past a
  // primitive's count hold it, so a read of them shows in the graph.
  const LO unused = n_nodes - 1;
  std::uniform_int_distribution<LO> node(-4, n_nodes - 2);
  std::vector<std::vector<LO>> stencils(n_stencils, std::vector<LO>(ns));
  for (auto& s : stencils)
    for (auto& v : s) v = node(rng);
  for (int a = 0; a < ns - 1; ++a) stencils[1][a] = stencils[0][a];  // two stencils alike but for the last node
  Kokkos::View<LO**, MemSpace> pn("pn", n_particles, ns);
  std::uniform_int_distribution<int> pick(0, n_stencils - 1);
  for (LO p = 0; p < n_particles; ++p) {
    const auto& s = stencils[pick(rng)];
    for (int a = 0; a < ns; ++a) pn(p, a) = s[a];
  }
  Kokkos::View<LO**, MemSpace> vn("vn", n_prims, nv);
  Kokkos::View<int*, MemSpace> vc("vc", n_prims);
  std::uniform_int_distribution<LO> vertex(0, n_nodes - 2);
  std::uniform_int_distribution<int> count(1, nv);
  for (LO f = 0; f < n_prims; ++f) {
    vc(f) = count(rng);
    for (int b = 0; b < nv; ++b) vn(f, b) = b < vc(f) ? vertex(rng) : unused;  // padding is never read
  }
  // Pairs sorted by particle (several per particle).
  std::vector<std::pair<LO, LO>> pairs;
  std::uniform_int_distribution<LO> particle(0, n_particles - 1), prim(0, n_prims - 1);
  for (long k = 0; k < n_pairs; ++k) pairs.emplace_back(particle(rng), prim(rng));
  std::sort(pairs.begin(), pairs.end());
  Kokkos::View<LO*, MemSpace> q("q", pairs.size()), j("j", pairs.size());
  for (std::size_t k = 0; k < pairs.size(); ++k) std::tie(q(k), j(k)) = pairs[k];

  Pairs expected;
  for (LO r = 0; r < n_nodes; ++r) expected.emplace(r, r);
  for (const auto& [p, f] : pairs) {
    std::vector<LO> s, v;
    for (int a = 0; a < ns; ++a)
      if (pn(p, a) >= 0) s.push_back(pn(p, a));
    for (int b = 0; b < vc(f); ++b) v.push_back(vn(f, b));
    for (LO a : s) {
      for (LO b : s) expected.emplace(a, b);
      for (LO b : v) {
        expected.emplace(a, b);
        expected.emplace(b, a);
      }
    }
    for (LO a : v)
      for (LO b : v) expected.emplace(a, b);
  }
  const Pairs got = built_graph(n_nodes, q, j, pn, vn, vc);
  EXPECT_EQ(got.size(), expected.size()) << "ns " << ns << ", nv " << nv << ", " << n_pairs << " pairs";
  EXPECT_TRUE(got == expected) << "ns " << ns << ", nv " << nv << ", " << n_pairs << " pairs";
}

}  // namespace

TEST(PairCouplings, RunsOfSharedStencilsGiveEveryPairsCouplings) {
  for (unsigned seed : {1u, 2u, 3u}) {
    check(9, 2, 400, seed);   // 2D: quadratic stencil, segments (and points: one vertex)
    check(27, 3, 400, seed);  // 3D: triangles, with fewer vertices too
  }
  check(9, 2, 1, 4);  // one pair
  check(27, 3, 0, 5);  // no pairs: the diagonal only
}
