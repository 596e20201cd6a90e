// MPI helpers that keep every rank in step: agreeing on a failure that happened on some ranks only
// (so no rank is left waiting in a collective call), and the all-to-all exchange of plain records.
#pragma once

#include <sinew/core/errors.hpp>

#include <Teuchos_Comm.hpp>
#include <Teuchos_DefaultMpiComm.hpp>
#include <mpi.h>

#include <cstdio>
#include <algorithm>
#include <cstring>
#include <ctime>
#include <stdexcept>
#include <string>
#include <type_traits>
#include <vector>

namespace sinew {

inline MPI_Comm raw_comm(const Teuchos::Comm<int>& comm) {
  if (auto mpi = dynamic_cast<const Teuchos::MpiComm<int>*>(&comm)) return *mpi->getRawMpiComm();
  return MPI_COMM_SELF;
}

// Runs fn on every rank, then agrees: when any rank threw, every rank throws the lowest failing rank's
// error (an InputError keeps its kind). fn must not itself call collectives that a failing rank skips.
template <class Fn>
void collectively(MPI_Comm comm, Fn&& fn) {
  int rank = 0, size = 1;
  MPI_Comm_rank(comm, &rank);
  MPI_Comm_size(comm, &size);
  std::string msg;
  int kind = -1;  // -1: not an InputError
  int failed = size;
  try {
    fn();
  } catch (const InputError& e) {
    msg = e.what();
    kind = static_cast<int>(e.kind);
    failed = rank;
  } catch (const std::exception& e) {
    msg = e.what();
    failed = rank;
  }
  int first = size;
  MPI_Allreduce(&failed, &first, 1, MPI_INT, MPI_MIN, comm);
  if (first == size) return;
  int len = static_cast<int>(msg.size());
  MPI_Bcast(&len, 1, MPI_INT, first, comm);
  MPI_Bcast(&kind, 1, MPI_INT, first, comm);
  msg.resize(len);
  MPI_Bcast(msg.data(), len, MPI_CHAR, first, comm);
  if (kind >= 0) throw InputError(msg, static_cast<InputErrorKind>(kind));
  throw std::runtime_error(msg);
}

// For an error this rank met inside collective work that the other ranks may not share (an exception
// from deep inside a linear solver or a preconditioner): waits up to `seconds` for every rank to meet
// one too (a non-blocking barrier on `comm`, a communicator only such meetings use). When they all do,
// it returns and the caller reports the error everywhere; when some do not, they are waiting in a
// collective call this rank left, so it prints the message and ends the job (MPI_Abort): better than a
// hang.
inline void meet_or_abort(MPI_Comm comm, const std::string& message, double seconds) {
  int size = 1, rank = 0;
  MPI_Comm_size(comm, &size);
  MPI_Comm_rank(comm, &rank);
  if (size == 1) return;
  MPI_Request request;
  MPI_Ibarrier(comm, &request);
  const double start = MPI_Wtime();
  for (int done = 0;;) {
    MPI_Test(&request, &done, MPI_STATUS_IGNORE);
    if (done) return;
    if (MPI_Wtime() - start > seconds) break;
    struct timespec pause {0, 1000000};
    nanosleep(&pause, nullptr);
  }
  std::fprintf(stderr, "sinew: error on rank %d that the other ranks did not meet within %g s: %s; aborting every rank\n", rank,
               seconds, message.c_str());
  std::fflush(stderr);
  MPI_Abort(MPI_COMM_WORLD, 1);
}

// send[r] goes to rank r; returns what each rank sent here, by source rank.
// chunk_bytes: the bytes per pair and round (0: 1 GiB / P; tests make it small to exercise the rounds).
template <class T>
std::vector<std::vector<T>> alltoallv(MPI_Comm comm, const std::vector<std::vector<T>>& send, long long chunk_bytes = 0) {
  static_assert(std::is_trivially_copyable_v<T>, "records are sent as bytes");
  int P = 1;
  MPI_Comm_size(comm, &P);
  std::vector<long long> sbytes(P), rbytes(P);
  for (int r = 0; r < P; ++r) sbytes[r] = static_cast<long long>(send[r].size() * sizeof(T));
  MPI_Alltoall(sbytes.data(), 1, MPI_LONG_LONG, rbytes.data(), 1, MPI_LONG_LONG, comm);
  // Exchanged in rounds of at most 1 GiB / P bytes per pair, so that MPI's int counts and displacements
  // (summed over the ranks of a round) never overflow, whatever the number of ranks.
  const long long chunk = chunk_bytes > 0 ? chunk_bytes : std::max(1LL, (1LL << 30) / P);
  std::vector<std::vector<T>> recv(P);
  for (int r = 0; r < P; ++r) recv[r].resize(static_cast<std::size_t>(rbytes[r]) / sizeof(T));
  for (long long offset = 0;; offset += chunk) {
    std::vector<int> sc(P), rc(P), sd(P + 1, 0), rd(P + 1, 0);
    long long left = 0;
    for (int r = 0; r < P; ++r) {
      sc[r] = static_cast<int>(std::max(0LL, std::min(chunk, sbytes[r] - offset)));
      rc[r] = static_cast<int>(std::max(0LL, std::min(chunk, rbytes[r] - offset)));
      sd[r + 1] = sd[r] + sc[r];
      rd[r + 1] = rd[r] + rc[r];
      left += sc[r] + rc[r];
    }
    long long any = left;
    MPI_Allreduce(&left, &any, 1, MPI_LONG_LONG, MPI_SUM, comm);
    if (any == 0) break;
    std::vector<char> sbuf(sd[P]), rbuf(rd[P]);
    for (int r = 0; r < P; ++r)
      if (sc[r] > 0) std::memcpy(sbuf.data() + sd[r], reinterpret_cast<const char*>(send[r].data()) + offset, sc[r]);
    MPI_Alltoallv(sbuf.data(), sc.data(), sd.data(), MPI_BYTE, rbuf.data(), rc.data(), rd.data(), MPI_BYTE, comm);
    for (int r = 0; r < P; ++r)
      if (rc[r] > 0) std::memcpy(reinterpret_cast<char*>(recv[r].data()) + offset, rbuf.data() + rd[r], rc[r]);
  }
  return recv;
}

// Every rank's `mine` concatenated in rank order, on every rank; `counts` (if given) receives each
// rank's item count. Meant for surface-sized data: more than 2 GiB in all is an error on every rank.
template <class T>
std::vector<T> allgatherv(MPI_Comm comm, const std::vector<T>& mine, std::vector<long long>* counts = nullptr) {
  static_assert(std::is_trivially_copyable_v<T>, "records are sent as bytes");
  int P = 1;
  MPI_Comm_size(comm, &P);
  long long n = static_cast<long long>(mine.size());
  std::vector<long long> all_n(P);
  MPI_Allgather(&n, 1, MPI_LONG_LONG, all_n.data(), 1, MPI_LONG_LONG, comm);
  long long total = 0;
  for (long long k : all_n) total += k;
  if (total * static_cast<long long>(sizeof(T)) > 2147483647LL)
    throw std::runtime_error("allgatherv: " + std::to_string(total * sizeof(T)) + " bytes exceed what one exchange carries");
  std::vector<int> bytes(P), displs(P, 0);
  for (int r = 0; r < P; ++r) {
    bytes[r] = static_cast<int>(all_n[r] * static_cast<long long>(sizeof(T)));
    if (r > 0) displs[r] = displs[r - 1] + bytes[r - 1];
  }
  std::vector<T> out(static_cast<std::size_t>(total));
  MPI_Allgatherv(mine.data(), bytes.empty() ? 0 : static_cast<int>(n * sizeof(T)), MPI_BYTE, out.data(), bytes.data(),
                 displs.data(), MPI_BYTE, comm);
  if (counts) *counts = all_n;
  return out;
}

}  // namespace sinew
