// The MPI implementation of Ranks (ranks.h); compiled only when CMake found MPI.
#ifdef CAUSTICA_MPI

#include <mpi.h>

#include <algorithm>
#include <chrono>
#include <cstdlib>
#include <cstring>
#include <thread>

#include "film/film.h"
#include "render/ranks.h"

namespace caustica {

namespace {

// FixedSum is __int128, which MPI has no type or sum for: 16 contiguous bytes and our own op.
// The op is exact integer addition, so it is associative and commutative, and MPI may reduce
// in any tree it likes without changing a bit (core/fixed_sum.h).
void add_fixed_sums(void* in, void* inout, int* len, MPI_Datatype*) {
  const char* a = static_cast<const char*>(in);
  char* b = static_cast<char*>(inout);
  for (int i = 0; i < *len; ++i) {
    // memcpy: MPI's internal buffers need not be 16-byte aligned.
    FixedSum x, y;
    std::memcpy(&x, a + 16 * size_t(i), 16);
    std::memcpy(&y, b + 16 * size_t(i), 16);
    y += x;
    std::memcpy(b + 16 * size_t(i), &y, 16);
  }
}

class MpiRanks final : public Ranks {
 public:
  MpiRanks() {
    MPI_Comm_rank(MPI_COMM_WORLD, &rank_);
    MPI_Comm_size(MPI_COMM_WORLD, &size_);
    MPI_Type_contiguous(int(sizeof(FixedSum)), MPI_BYTE, &fixed_type_);
    MPI_Type_commit(&fixed_type_);
    MPI_Op_create(add_fixed_sums, /*commute=*/1, &fixed_add_);
    // Shared-learning sums get their own communicator: ranks start progress rounds (non-blocking
    // collectives on MPI_COMM_WORLD) at different points relative to them, and collectives on
    // one communicator must be issued in the same order by every rank.
    MPI_Comm_dup(MPI_COMM_WORLD, &learning_);
  }
  ~MpiRanks() override {
    if (round_pending_) MPI_Wait(&round_, MPI_STATUS_IGNORE);
    MPI_Comm_free(&learning_);
    MPI_Op_free(&fixed_add_);
    MPI_Type_free(&fixed_type_);
    MPI_Finalize();
  }

  int rank() const override { return rank_; }
  int size() const override { return size_; }

  void start_round(const RoundState& mine) override {
    send_[0] = mine.iterations;
    send_[1] = mine.rays;
    send_[2] = mine.finished;
    send_[3] = mine.stop;
    send_[4] = mine.root_micros;
    send_[5] = mine.interrupted;
    MPI_Iallreduce(send_, recv_, kRoundFields, MPI_UINT64_T, MPI_SUM, MPI_COMM_WORLD, &round_);
    round_pending_ = true;
  }

  bool poll_round(RoundState* totals, bool wait) override {
    if (!round_pending_) return false;
    for (;;) {
      int done = 0;
      MPI_Test(&round_, &done, MPI_STATUS_IGNORE);
      if (done) break;
      if (!wait) return false;
      // MPI_Wait would spin a core at 100% (Open MPI polls); a rank that has finished its
      // iterations should leave the cores to ranks still rendering on the same node.
      std::this_thread::sleep_for(std::chrono::milliseconds(1));
    }
    round_pending_ = false;
    totals->iterations = recv_[0];
    totals->rays = recv_[1];
    totals->finished = recv_[2];
    totals->stop = recv_[3];
    totals->root_micros = recv_[4];
    totals->interrupted = recv_[5];
    return true;
  }

  void sum_films(const Film& mine, Film* root_total) override {
    const std::span<const FixedSum> send = mine.sums();
    FixedSum* recv = rank_ == 0 ? root_total->sums().data() : nullptr;
    const bool in_place = rank_ == 0 && root_total == &mine;
    for (size_t at = 0; at < send.size(); at += kPiece) {
      const int n = int(std::min(kPiece, send.size() - at));
      const void* from = in_place ? MPI_IN_PLACE : static_cast<const void*>(send.data() + at);
      MPI_Reduce(from, recv ? recv + at : nullptr, n, fixed_type_, fixed_add_, 0, MPI_COMM_WORLD);
    }
    const uint64_t counts[2] = {mine.iterations(), mine.nonfinite_count()};
    uint64_t total[2] = {0, 0};
    MPI_Reduce(counts, total, 2, MPI_UINT64_T, MPI_SUM, 0, MPI_COMM_WORLD);
    if (rank_ == 0) root_total->set_counts(uint32_t(total[0]), total[1]);
  }

  bool all_sum_films(const Film& mine, Film* total, bool stop) override {
    const std::span<const FixedSum> send = mine.sums();
    FixedSum* recv = total->sums().data();
    for (size_t at = 0; at < send.size(); at += kPiece) {
      const int n = int(std::min(kPiece, send.size() - at));
      MPI_Allreduce(send.data() + at, recv + at, n, fixed_type_, fixed_add_, learning_);
    }
    const uint64_t counts[3] = {mine.iterations(), mine.nonfinite_count(), stop ? 1u : 0u};
    uint64_t sum[3] = {0, 0, 0};
    MPI_Allreduce(counts, sum, 3, MPI_UINT64_T, MPI_SUM, learning_);
    total->set_counts(uint32_t(sum[0]), sum[1]);
    return sum[2] > 0;
  }

  bool any_stops(bool stop) override {
    int mine = stop ? 1 : 0, any = 0;
    MPI_Allreduce(&mine, &any, 1, MPI_INT, MPI_MAX, learning_);
    return any > 0;
  }

  void all_sum(std::span<FixedSum> sums) override {
    for (size_t at = 0; at < sums.size(); at += kPiece) {
      const int n = int(std::min(kPiece, sums.size() - at));
      MPI_Allreduce(MPI_IN_PLACE, sums.data() + at, n, fixed_type_, fixed_add_, learning_);
    }
  }

  void sum_to_root(std::span<FixedSum> sums) override {
    for (size_t at = 0; at < sums.size(); at += kPiece) {
      const int n = int(std::min(kPiece, sums.size() - at));
      if (rank_ == 0)
        MPI_Reduce(MPI_IN_PLACE, sums.data() + at, n, fixed_type_, fixed_add_, 0, MPI_COMM_WORLD);
      else
        MPI_Reduce(sums.data() + at, nullptr, n, fixed_type_, fixed_add_, 0, MPI_COMM_WORLD);
    }
  }

  int agree(int status, const std::string& mine, std::string* message) override {
    message->clear();
    int worst = 0;
    MPI_Allreduce(&status, &worst, 1, MPI_INT, MPI_MAX, MPI_COMM_WORLD);
    if (worst == 0) return 0;
    const int candidate = status != 0 ? rank_ : size_;
    int first = size_;
    MPI_Allreduce(&candidate, &first, 1, MPI_INT, MPI_MIN, MPI_COMM_WORLD);
    if (first == 0) return worst;  // rank 0 failed and has printed its own message
    // The first failing rank's message travels to everyone (a broadcast: all ranks take part).
    uint64_t length = rank_ == first ? mine.size() : 0;
    MPI_Bcast(&length, 1, MPI_UINT64_T, first, MPI_COMM_WORLD);
    std::string text = rank_ == first ? mine : std::string(length, '\0');
    MPI_Bcast(text.data(), int(length), MPI_CHAR, first, MPI_COMM_WORLD);
    if (rank_ == 0)
      *message = "rank " + std::to_string(first) + " of " + std::to_string(size_) + ": " + text;
    return worst;
  }

  void wait_all() override {
    MPI_Request barrier;
    MPI_Ibarrier(MPI_COMM_WORLD, &barrier);
    for (int done = 0;;) {
      MPI_Test(&barrier, &done, MPI_STATUS_IGNORE);
      if (done) return;
      std::this_thread::sleep_for(std::chrono::milliseconds(10));
    }
  }

  void abort(int exit_code) override {
    MPI_Abort(MPI_COMM_WORLD, exit_code);
    std::_Exit(exit_code);
  }

 private:
  // MPI counts are int: reduce in pieces of 2^26 sums (1 GiB).
  static constexpr size_t kPiece = size_t(1) << 26;
  int rank_ = 0, size_ = 1;
  MPI_Comm learning_ = MPI_COMM_NULL;
  MPI_Datatype fixed_type_;
  MPI_Op fixed_add_;
  MPI_Request round_ = MPI_REQUEST_NULL;
  bool round_pending_ = false;
  static constexpr int kRoundFields = 6;  // RoundState's fields
  uint64_t send_[kRoundFields] = {}, recv_[kRoundFields] = {};
};

bool launched_by_mpi() {
  for (const char* name : {"OMPI_COMM_WORLD_SIZE", "PMI_SIZE", "PMIX_RANK", "MPI_LOCALNRANKS"})
    if (std::getenv(name)) return true;
  return false;
}

}  // namespace

std::unique_ptr<Ranks> start_ranks(int* argc, char*** argv) {
  // Started without a launcher the binary behaves as before, and does not pay MPI_Init's
  // singleton start-up.
  if (!launched_by_mpi()) return std::make_unique<SingleProcess>();
  int provided = 0;
  // Only the main thread calls MPI; TBB's workers never do.
  MPI_Init_thread(argc, argv, MPI_THREAD_FUNNELED, &provided);
  return std::make_unique<MpiRanks>();
}

bool built_with_mpi() { return true; }

}  // namespace caustica

#endif  // CAUSTICA_MPI
