#pragma once
// Checks shared by the MPI tests.
#include <gtest/gtest.h>

#include <Teuchos_CommHelpers.hpp>
#include <vector>

#include "solver/tpetra_types.hpp"

namespace bfemp::fixtures {

// Every rank took the same Newton iterations in every step (global decisions).
inline void expect_same_on_every_rank(const Comm& world, const std::vector<int>& iterations) {
  for (int it : iterations) {
    int lo = 0, hi = 0;
    Teuchos::reduceAll(world, Teuchos::REDUCE_MIN, it, Teuchos::outArg(lo));
    Teuchos::reduceAll(world, Teuchos::REDUCE_MAX, it, Teuchos::outArg(hi));
    EXPECT_EQ(lo, hi);
  }
}

}  // namespace bfemp::fixtures
