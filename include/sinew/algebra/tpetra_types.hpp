// The Tpetra types every part of the algebra layer and above speaks: one scalar (double), Tpetra's
// default ordinals and node (the Kokkos default execution space).
#pragma once

#include <Tpetra_CrsGraph_fwd.hpp>
#include <Tpetra_CrsMatrix_fwd.hpp>
#include <Tpetra_Export_fwd.hpp>
#include <Tpetra_Import_fwd.hpp>
#include <Tpetra_Map.hpp>
#include <Tpetra_MultiVector_fwd.hpp>
#include <Tpetra_Vector_fwd.hpp>

namespace sinew {

using Map = Tpetra::Map<>;
using LO = Map::local_ordinal_type;
using GO = Map::global_ordinal_type;
using NodeType = Map::node_type;
using Vector = Tpetra::Vector<double, LO, GO, NodeType>;
using MultiVector = Tpetra::MultiVector<double, LO, GO, NodeType>;
using CrsGraph = Tpetra::CrsGraph<LO, GO, NodeType>;
using CrsMatrix = Tpetra::CrsMatrix<double, LO, GO, NodeType>;
using Import = Tpetra::Import<LO, GO, NodeType>;
using Export = Tpetra::Export<LO, GO, NodeType>;

}  // namespace sinew
