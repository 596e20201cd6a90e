// Element chunks coloured so that the element loop can add into the matrix without atomic operations.
// An atomic add of a double is a compare-and-swap loop on the host, and hex8 makes 576 of them per
// element: a quarter of the element loop's time on one thread (docs/performance.md). Instead, a list of
// elements is cut into chunks of consecutive elements (consecutive in the mesh's order, so a chunk's
// rows stay in cache while one thread sums into them), and the chunks get colours such that no two
// chunks of one colour touch the same node. One launch per colour then runs its chunks in parallel with
// plain adds, and the sums no longer depend on the number of threads.
#pragma once

#include <cstddef>
#include <vector>

namespace sinew {

struct ElementChunks {
  std::vector<int> elements;      // the input elements, reordered so that each chunk is contiguous
  std::vector<int> chunk_begin;   // chunk c is elements[chunk_begin[c], chunk_begin[c + 1])
  std::vector<int> colour_begin;  // colour k is chunks [colour_begin[k], colour_begin[k + 1])
  int colours() const { return colour_begin.empty() ? 0 : static_cast<int>(colour_begin.size()) - 1; }
};

// Greedy colouring of the chunks of `elements` (local element ids into `conn`, row-major element x
// node, `npe` nodes per element, node ids below `nodes`), chunk_size elements per chunk. Chunks keep
// their order within a colour.
ElementChunks colour_element_chunks(const std::vector<int>& elements, const std::vector<int>& conn, int npe,
                                    std::size_t nodes, int chunk_size);

}  // namespace sinew
