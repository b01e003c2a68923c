#pragma once
// bfemp's arrays seen as CHOLMOD objects, without copies (CholmodDirect and
// BlockCholmod): a symmetric matrix as compressed columns whose upper
// triangle CHOLMOD reads (stype 1: for a symmetric matrix stored by rows the
// row arrays are the column arrays), and a dense column. Preconditions: the
// index arrays sorted within each column, n = p.size() - 1, and the arrays
// alive and unmoved while CHOLMOD uses the view.
#include <cholmod.h>

#include <cstddef>
#include <vector>

namespace bfemp {

inline cholmod_sparse symmetric_csc_view(std::vector<SuiteSparse_long>& p, std::vector<SuiteSparse_long>& i,
                                         double* x) {
  cholmod_sparse S{};
  S.nrow = S.ncol = p.size() - 1;
  S.nzmax = i.size();
  S.p = p.data();
  S.i = i.data();
  S.x = x;
  S.stype = 1;
  S.itype = CHOLMOD_LONG;
  S.xtype = CHOLMOD_REAL;
  S.dtype = CHOLMOD_DOUBLE;
  S.sorted = 1;
  S.packed = 1;
  return S;
}

inline cholmod_dense dense_column_view(double* x, std::size_t n) {
  cholmod_dense B{};
  B.nrow = n;
  B.ncol = 1;
  B.nzmax = n;
  B.d = n;
  B.x = x;
  B.xtype = CHOLMOD_REAL;
  B.dtype = CHOLMOD_DOUBLE;
  return B;
}

}  // namespace bfemp
