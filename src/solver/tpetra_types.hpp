#pragma once
// Tpetra objects of the linear system (only the instantiated types link).
#include <Tpetra_CrsGraph_decl.hpp>
#include <Tpetra_CrsMatrix_decl.hpp>
#include <Tpetra_MultiVector_decl.hpp>
#include <Tpetra_Operator.hpp>
#include <Tpetra_Vector_decl.hpp>

#include "core/types.hpp"

namespace bfemp {
using Graph = Tpetra::CrsGraph<LO, GO, Node>;
using Matrix = Tpetra::CrsMatrix<double, LO, GO, Node>;
using MultiVec = Tpetra::MultiVector<double, LO, GO, Node>;
using Vector = Tpetra::Vector<double, LO, GO, Node>;
using Operator = Tpetra::Operator<double, LO, GO, Node>;
using Comm = Teuchos::Comm<int>;
}  // namespace bfemp
