// Helpers for tests on distributed Tpetra objects.
#pragma once

#include <sinew/algebra/system.hpp>

#include <Tpetra_Import.hpp>
#include <Tpetra_Vector.hpp>

#include <vector>

namespace sinew::test {

// The whole vector on every rank, indexed by global id.
inline std::vector<double> gather(const Vector& v) {
  auto map = v.getMap();
  auto all = Tpetra::createLocalMapWithNode<LO, GO, NodeType>(map->getGlobalNumElements(), map->getComm());
  Vector full(all);
  Import imp(map, all);
  full.doImport(v, imp, Tpetra::INSERT);
  auto h = full.getLocalViewHost(Tpetra::Access::ReadOnly);
  return std::vector<double>(h.data(), h.data() + h.extent(0));
}

}  // namespace sinew::test
