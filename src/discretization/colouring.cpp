#include <sinew/discretization/colouring.hpp>

#include <algorithm>
#include <cstdint>
#include <stdexcept>

namespace sinew {

ElementChunks colour_element_chunks(const std::vector<int>& elements, const std::vector<int>& conn, int npe,
                                    std::size_t nodes, int chunk_size) {
  if (chunk_size < 1) throw std::invalid_argument("colour_element_chunks: chunk size must be positive");
  const std::size_t n = elements.size(), n_chunks = (n + chunk_size - 1) / chunk_size;
  // used[node]: the colours of the chunks coloured so far that touch the node, 64 per word; a chunk
  // takes the lowest colour none of its nodes has.
  std::vector<std::vector<std::uint64_t>> used(1);
  used[0].assign(nodes, 0);
  std::vector<int> colour_of(n_chunks);
  int n_colours = 0;
  for (std::size_t c = 0; c < n_chunks; ++c) {
    const std::size_t begin = c * chunk_size, end = std::min(n, begin + chunk_size);
    int colour = -1;
    for (std::size_t word = 0; colour < 0; ++word) {
      if (word == used.size()) used.emplace_back(nodes, 0);
      std::uint64_t taken = 0;
      for (std::size_t k = begin; k < end; ++k)
        for (int a = 0; a < npe; ++a) taken |= used[word][conn[static_cast<std::size_t>(elements[k]) * npe + a]];
      if (~taken != 0) colour = static_cast<int>(64 * word) + __builtin_ctzll(~taken);
    }
    const std::uint64_t bit = std::uint64_t{1} << (colour % 64);
    for (std::size_t k = begin; k < end; ++k)
      for (int a = 0; a < npe; ++a) used[colour / 64][conn[static_cast<std::size_t>(elements[k]) * npe + a]] |= bit;
    colour_of[c] = colour;
    n_colours = std::max(n_colours, colour + 1);
  }
  // Chunks sorted by colour, stable; elements follow their chunks.
  std::vector<int> order(n_chunks);
  for (std::size_t c = 0; c < n_chunks; ++c) order[c] = static_cast<int>(c);
  std::stable_sort(order.begin(), order.end(), [&](int x, int y) { return colour_of[x] < colour_of[y]; });
  ElementChunks out;
  out.elements.reserve(n);
  out.chunk_begin.reserve(n_chunks + 1);
  out.colour_begin.assign(n_colours + 1, 0);
  for (int c : order) {
    out.chunk_begin.push_back(static_cast<int>(out.elements.size()));
    const std::size_t begin = static_cast<std::size_t>(c) * chunk_size, end = std::min(n, begin + chunk_size);
    for (std::size_t k = begin; k < end; ++k) out.elements.push_back(elements[k]);
    ++out.colour_begin[colour_of[c] + 1];
  }
  out.chunk_begin.push_back(static_cast<int>(out.elements.size()));
  for (int k = 0; k < n_colours; ++k) out.colour_begin[k + 1] += out.colour_begin[k];
  return out;
}

}  // namespace sinew
