// A plain Kokkos CRS matrix with the one operation the element kernels need (sumIntoValues, atomically
// when asked, with KokkosSparse's meaning), for builds without Trilinos: the device tests and benchmarks. The host
// solver uses Tpetra's local matrix instead, through the same CrsTarget.
#pragma once

#include <Kokkos_Core.hpp>

namespace sinew {

template <class MemorySpace>
struct LocalCsr {
  using memory_space = MemorySpace;
  Kokkos::View<const int*, MemorySpace> row_map;  // rows + 1 offsets
  Kokkos::View<const int*, MemorySpace> entries;  // column indices, sorted within each row
  Kokkos::View<double*, MemorySpace> values;

  // Adds vals[k] at (row, cols[k]) for the columns present in the row; returns how many were.
  KOKKOS_INLINE_FUNCTION int sumIntoValues(int row, const int* cols, int n, const double* vals, bool /*sorted*/,
                                           bool atomic) const {
    const int begin = row_map(row), end = row_map(row + 1);
    int found = 0;
    for (int k = 0; k < n; ++k) {
      int lo = begin, hi = end;  // binary search: rows hold up to 81 entries for hex8
      while (lo < hi) {
        const int mid = (lo + hi) / 2;
        if (entries(mid) < cols[k])
          lo = mid + 1;
        else
          hi = mid;
      }
      if (lo < end && entries(lo) == cols[k]) {
        if (atomic)
          Kokkos::atomic_add(&values(lo), vals[k]);
        else
          values(lo) += vals[k];
        ++found;
      }
    }
    return found;
  }
};

}  // namespace sinew
