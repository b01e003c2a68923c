#pragma once
// How the supernodes of a factor are shared among threads in the triangular
// solves (SingleFactor::solve).
//
// Math. Column j of L has entries only in rows that are ancestors of j in the
// elimination tree, so the forward solve of a supernode changes only its
// ancestors' rows, and the backward solve of a supernode reads only them.
// Disjoint subtrees are therefore independent in both solves, except for the
// rows of their common ancestors. The schedule splits the supernodal tree
// into
//  - subtrees, each solved whole by one thread: its updates to rows outside it
//    (all of them its ancestors' rows) go to the thread's own buffer, summed
//    into the vector in thread order after the subtrees;
//  - the top: the supernodes above the subtrees, solved after them (forward)
//    or before them (backward) in tree order; the large ones by all threads at
//    once, each thread taking a contiguous range of the rows below each panel
//    of columns; the small ones by thread 0.
// The split takes the heaviest subtree apart (its root joins the top, its
// children become subtrees) until none weighs more than the total over
// kSubtreesPerThread x threads; the subtrees are dealt to threads largest
// first, each to the least loaded (weight: stored entries).
//
// Preconditions: CHOLMOD's supernodes in postorder (each subtree a contiguous
// range of supernodes and columns, a parent numbered after its children;
// CHOLMOD's default), and each supernode's rows ascending, its own columns
// first; build() returns false otherwise and the solve stays on one thread. The schedule depends only on the pattern and the thread count,
// so a solve is deterministic for a given thread count.
#include <cholmod.h>

#include <cstddef>
#include <vector>

namespace bfemp {

struct SupernodeSchedule {
  using Long = SuiteSparse_long;
  static constexpr int kSubtreesPerThread = 4;
  // A top supernode with at least this many stored entries is solved by all
  // threads (each panel costs two barriers).
  static constexpr Long kSharedEntries = 1 << 16;
  static constexpr Long kPanel = 64;  // columns per panel of a shared supernode

  int threads = 0;  // 0: none built (solve on one thread)
  // Thread t solves subtrees order[thread_begin[t] .. thread_begin[t+1]); subtree
  // q is supernodes first[q] .. root[q] and owns the columns below col_end[q].
  std::vector<int> thread_begin, order;
  std::vector<Long> first, root, col_end;
  std::vector<Long> top;          // the top's supernodes, ascending (children first)
  std::vector<char> top_shared;   // per entry of top: solved by all threads
  std::vector<Long> top_rows;     // the top's columns, ascending
  std::vector<Long> top_index;    // column -> its index in top_rows, or -1
  double top_fraction = 0;        // the top's share of the stored entries (the part not in subtrees)

  // Builds the schedule for `threads` threads from the factor's supernodal
  // pattern (super, pi, s as CHOLMOD stores them, ns supernodes, n columns).
  bool build(int threads, std::size_t n, std::size_t ns, const Long* super, const Long* pi, const Long* s);
  void clear() {
    threads = 0;
    thread_begin.clear(), order.clear(), first.clear(), root.clear(), col_end.clear();
    top.clear(), top_shared.clear(), top_rows.clear(), top_index.clear();
    top_fraction = 0;
  }
};

}  // namespace bfemp
