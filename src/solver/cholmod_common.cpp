#include "solver/cholmod_common.hpp"

#include <omp.h>

namespace bfemp {

void start_cholmod(cholmod_common& c) {
  cholmod_l_start(&c);
  c.print = 0;
  c.error_handler = nullptr;
  c.final_ll = 1;
  c.nrelax[0] = 16;
  c.nrelax[1] = 64;
  c.nrelax[2] = 128;
}

CholmodSerialScope::CholmodSerialScope() {
  if (omp_in_parallel()) return;
  saved_ = omp_get_max_active_levels();
  omp_set_max_active_levels(0);
}

CholmodSerialScope::~CholmodSerialScope() {
  if (saved_ >= 0) omp_set_max_active_levels(saved_);
}

}  // namespace bfemp
