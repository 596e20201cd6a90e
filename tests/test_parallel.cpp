// Sinew's own MPI plumbing (core/collective.hpp) on the ranks and threads CTest gives it: the
// configuration really is what the variant asks for; the chunked all-to-all exchange, the all-gather
// and the agreement on errors that only some ranks meet. (Kernels on Serial against OpenMP and on 1
// against 2 ranks: test_assembly, BackendsAndRanksAgree.)
#include <sinew/core/collective.hpp>
#include <sinew/core/errors.hpp>

#include <Kokkos_Core.hpp>
#include <Tpetra_Core.hpp>
#include <gtest/gtest.h>

#include <cstdlib>
#include <numeric>

using namespace sinew;

namespace {
MPI_Comm world() { return raw_comm(*Tpetra::getDefaultComm()); }
int rank() { return Tpetra::getDefaultComm()->getRank(); }
int size() { return Tpetra::getDefaultComm()->getSize(); }
}  // namespace

// Every variant says what it expects (CMake sets both variables), so the test cannot pass by default.
TEST(Parallel, ThreadsAndRanksAsConfigured) {
  const char* t = std::getenv("SINEW_EXPECT_THREADS");
  const char* r = std::getenv("SINEW_EXPECT_RANKS");
  ASSERT_TRUE(t && r) << "SINEW_EXPECT_THREADS and SINEW_EXPECT_RANKS must be set by the test's variant";
  EXPECT_EQ(Kokkos::DefaultExecutionSpace::concurrency(), std::atoi(t));
  EXPECT_EQ(size(), std::atoi(r));
}

// Records of uneven sizes to every rank (itself included), in rounds far smaller than the messages
// (3 bytes per pair and round: records split across rounds), arrive whole and in order.
TEST(Parallel, AllToAllInRoundsDeliversEveryRecord) {
  struct Record {
    long long from, to, k;
    double x;
  };
  std::vector<std::vector<Record>> send(size());
  for (int r = 0; r < size(); ++r)
    for (long long k = 0; k < 5 + 3 * r + 7 * rank(); ++k) send[r].push_back({rank(), r, k, 0.5 * k + r});
  for (long long chunk : {3LL, 64LL, 0LL}) {
    const auto recv = alltoallv(world(), send, chunk);
    ASSERT_EQ(recv.size(), static_cast<std::size_t>(size()));
    for (int r = 0; r < size(); ++r) {
      ASSERT_EQ(recv[r].size(), static_cast<std::size_t>(5 + 3 * rank() + 7 * r)) << "chunk " << chunk;
      for (std::size_t k = 0; k < recv[r].size(); ++k) {
        EXPECT_EQ(recv[r][k].from, r);
        EXPECT_EQ(recv[r][k].to, rank());
        EXPECT_EQ(recv[r][k].k, static_cast<long long>(k));
        EXPECT_EQ(recv[r][k].x, 0.5 * k + rank());
      }
    }
  }
}

TEST(Parallel, AllGatherConcatenatesInRankOrder) {
  std::vector<int> mine(rank() + 2, rank());
  std::vector<long long> counts;
  const auto all = allgatherv(world(), mine, &counts);
  std::vector<int> expect;
  for (int r = 0; r < size(); ++r) expect.insert(expect.end(), r + 2, r);
  EXPECT_EQ(all, expect);
  ASSERT_EQ(counts.size(), static_cast<std::size_t>(size()));
  for (int r = 0; r < size(); ++r) EXPECT_EQ(counts[r], r + 2);
}

// An error met on the last rank only is thrown on every rank with that rank's message (and its kind);
// an error met on every rank lets them meet and go on together.
TEST(Parallel, AnErrorOnOneRankIsAnErrorOnEvery) {
  try {
    collectively(world(), [&] {
      if (rank() == size() - 1) throw InputError("only the last rank saw this", InputErrorKind::BadMesh);
    });
    FAIL() << "no error";
  } catch (const InputError& e) {
    EXPECT_EQ(e.kind, InputErrorKind::BadMesh);
    EXPECT_STREQ(e.what(), "only the last rank saw this");
  }
  meet_or_abort(world(), "every rank met this", 30.0);  // returns: everybody is here
  SUCCEED();
}
