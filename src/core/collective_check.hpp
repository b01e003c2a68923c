#pragma once
// A check of rank-local data (this rank's particles, its part of the mesh)
// whose verdict every rank must share before the next collective call: runs
// check(); an std::invalid_argument on any rank is thrown on every rank, with
// the message of the lowest rank that threw (broadcast from it), so the
// ranks stop together instead of the others waiting in the next collective.
// Collective: every rank calls it at the same point.
#include <Teuchos_Comm.hpp>
#include <Teuchos_CommHelpers.hpp>
#include <functional>
#include <limits>
#include <stdexcept>
#include <string>

namespace bfemp {

inline void collective_check(const Teuchos::Comm<int>& comm, const std::function<void()>& check) {
  std::string msg;
  bool failed = false;
  try {
    check();
  } catch (const std::invalid_argument& e) {
    msg = e.what();
    failed = true;
  }
  if (comm.getSize() == 1) {
    if (failed) throw std::invalid_argument(msg);
    return;
  }
  const int mine = failed ? comm.getRank() : std::numeric_limits<int>::max();
  int first = 0;
  Teuchos::reduceAll(comm, Teuchos::REDUCE_MIN, mine, Teuchos::outArg(first));
  if (first == std::numeric_limits<int>::max()) return;
  int len = static_cast<int>(msg.size());
  Teuchos::broadcast(comm, first, Teuchos::outArg(len));
  std::string text(static_cast<std::size_t>(len), ' ');
  if (comm.getRank() == first) text = msg;
  if (len > 0) Teuchos::broadcast(comm, first, len, text.data());
  throw std::invalid_argument(text);
}

}  // namespace bfemp
