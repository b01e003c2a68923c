#include "solver/supernode_schedule.hpp"

#include <algorithm>
#include <queue>
#include <utility>

namespace bfemp {

bool SupernodeSchedule::build(int nthreads, std::size_t n, std::size_t ns, const Long* super, const Long* pi,
                              const Long* s) {
  clear();
  if (nthreads < 2 || ns == 0) return false;
  // The supernodal tree: a supernode's parent holds its first row below its columns.
  std::vector<Long> owner(n);
  for (std::size_t k = 0; k < ns; ++k)
    for (Long j = super[k]; j < super[k + 1]; ++j) owner[static_cast<std::size_t>(j)] = static_cast<Long>(k);
  std::vector<Long> parent(ns, -1), weight(ns), size(ns, 1), lowest(ns);
  for (std::size_t k = 0; k < ns; ++k) {
    const Long nscol = super[k + 1] - super[k], nsrow = pi[k + 1] - pi[k];
    for (Long i = 0; i < nsrow; ++i) {  // its columns, then rows below them, ascending
      const Long r = s[pi[k] + i];
      if (i < nscol ? r != super[k] + i : (r < super[k + 1] || (i > 0 && r <= s[pi[k] + i - 1])) || r >= static_cast<Long>(n))
        return false;
    }
    weight[k] = nscol * nsrow;
    lowest[k] = static_cast<Long>(k);
    if (nsrow > nscol) {
      parent[k] = owner[static_cast<std::size_t>(s[pi[k] + nscol])];
      if (parent[k] <= static_cast<Long>(k)) return false;  // not a postorder
    }
  }
  Long total = 0;
  for (std::size_t k = 0; k < ns; ++k) {  // children before parents: subtree sums
    total += weight[k];
    if (parent[k] >= 0) {
      const auto p = static_cast<std::size_t>(parent[k]);
      size[p] += size[k];
      lowest[p] = std::min(lowest[p], lowest[k]);
    }
  }
  std::vector<Long> subtree_weight(weight);
  for (std::size_t k = 0; k < ns; ++k)
    if (parent[k] >= 0) subtree_weight[static_cast<std::size_t>(parent[k])] += subtree_weight[k];
  for (std::size_t k = 0; k < ns; ++k)  // each subtree a contiguous range ending at its root
    if (lowest[k] + size[k] - 1 != static_cast<Long>(k)) return false;
  std::vector<Long> child_begin(ns + 1, 0), children(ns);
  for (std::size_t k = 0; k < ns; ++k)
    if (parent[k] >= 0) ++child_begin[static_cast<std::size_t>(parent[k]) + 1];
  for (std::size_t k = 0; k < ns; ++k) child_begin[k + 1] += child_begin[k];
  {
    std::vector<Long> fill(child_begin.begin(), child_begin.end() - 1);
    for (std::size_t k = 0; k < ns; ++k)
      if (parent[k] >= 0) children[static_cast<std::size_t>(fill[static_cast<std::size_t>(parent[k])]++)] = static_cast<Long>(k);
  }
  // Split the heaviest subtree until every one is light enough.
  using Item = std::pair<Long, Long>;  // (subtree weight, root): the heaviest first, ties by root
  std::priority_queue<Item> heap;
  for (std::size_t k = 0; k < ns; ++k)
    if (parent[k] < 0) heap.emplace(subtree_weight[k], static_cast<Long>(k));
  const Long limit = total / (static_cast<Long>(kSubtreesPerThread) * nthreads);
  std::vector<char> in_top(ns, 0);
  while (!heap.empty() && heap.top().first > limit) {
    const Long k = heap.top().second;
    const auto ku = static_cast<std::size_t>(k);
    if (child_begin[ku] == child_begin[ku + 1]) break;  // a heavy leaf: the heaviest stays whole
    heap.pop();
    in_top[ku] = 1;
    for (Long c = child_begin[ku]; c < child_begin[ku + 1]; ++c)
      heap.emplace(subtree_weight[static_cast<std::size_t>(children[static_cast<std::size_t>(c)])],
                   children[static_cast<std::size_t>(c)]);
  }
  std::vector<Item> subtrees;
  while (!heap.empty()) subtrees.push_back(heap.top()), heap.pop();  // heaviest first
  // Deal them to threads, each to the least loaded so far.
  std::vector<Long> load(static_cast<std::size_t>(nthreads), 0);
  std::vector<std::vector<int>> dealt(static_cast<std::size_t>(nthreads));
  for (std::size_t q = 0; q < subtrees.size(); ++q) {
    const auto t = static_cast<std::size_t>(std::min_element(load.begin(), load.end()) - load.begin());
    load[t] += subtrees[q].first;
    dealt[t].push_back(static_cast<int>(q));
  }
  for (const auto& [w, r] : subtrees) {
    const auto ru = static_cast<std::size_t>(r);
    root.push_back(r);
    first.push_back(lowest[ru]);
    col_end.push_back(super[ru + 1]);
  }
  thread_begin.assign(1, 0);
  for (const auto& d : dealt) {
    order.insert(order.end(), d.begin(), d.end());
    thread_begin.push_back(static_cast<int>(order.size()));
  }
  top_index.assign(n, -1);
  Long top_weight = 0;
  for (std::size_t k = 0; k < ns; ++k) {
    if (!in_top[k]) continue;
    top.push_back(static_cast<Long>(k));
    top_shared.push_back(weight[k] >= kSharedEntries ? 1 : 0);
    top_weight += weight[k];
    for (Long j = super[k]; j < super[k + 1]; ++j) {
      top_index[static_cast<std::size_t>(j)] = static_cast<Long>(top_rows.size());
      top_rows.push_back(j);
    }
  }
  top_fraction = total > 0 ? static_cast<double>(top_weight) / static_cast<double>(total) : 0.0;
  threads = nthreads;
  return true;
}

}  // namespace bfemp
