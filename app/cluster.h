// Work split across processes (issue "Past one machine"): MPI ranks under `mpirun -np N`, or
// one part of a Slurm job array (`--part I/N`, merged afterwards by `freqlab merge`). Random
// numbers depend on (seed, frame, pixel or texel, sample) only, so a part computes exactly what
// one process would have computed for the same items: outputs are byte-identical for any split.
//
// | item split     | which items part p of n takes                                        |
// |----------------|------------------------------------------------------------------------|
// | round robin    | frames / texel rows / study configurations first + p, first + p + n … |
// | contiguous     | method A's cache: one chunk of frames each, warmed over K frames before |
//
// MPI is initialised only when the process was started by an MPI launcher (its environment
// says so): a freqlab built with MPI runs alone exactly as one built without it.
#pragma once

#include <string>
#include <utility>
#include <vector>

namespace freqlab {

// Which part of the work this process does.
struct WorkPart {
    int index = 0;
    int count = 1;
    bool whole() const { return count == 1; }
};
// "I/N" with 0 <= I < N; throws Error naming `flag`.
WorkPart parse_work_part(const std::string& text, const std::string& flag);
// Round robin: items first + index, first + index + count, ... below last.
std::vector<int> round_robin_items(int first, int last, WorkPart part);
// Contiguous: the index-th of `count` near-equal chunks of [first, last).
std::pair<int, int> contiguous_items(int first, int last, WorkPart part);
// "0, 4, 8" (at most a few numbers, then "... (N in all)") for messages.
std::string describe_items(const std::vector<int>& items);

// The MPI world (a single process when MPI is not built or not launched).
class Cluster {
  public:
    static Cluster& world();
    // Call first in main(); MPI_Init_thread only under an MPI launcher.
    void start(int* argc, char*** argv);
    void finish();  // MPI_Finalize when started
    int rank() const { return rank_; }
    int size() const { return size_; }
    bool distributed() const { return size_ > 1; }
    WorkPart part() const { return {rank_, size_}; }
    // What this rank is doing, for the message if it fails ("frames 1, 3, 5").
    void set_work(const std::string& work) { work_ = work; }
    const std::string& work() const { return work_; }

    // Point to point, tagged (only between start() and finish()). receive_any returns the
    // sender's rank with the bytes.
    void send(int to, int tag, const std::string& bytes) const;
    std::string receive(int from, int tag) const;
    std::pair<int, std::string> receive_any(int tag) const;
    void barrier() const;
    // Every rank's bytes at rank 0 (index = rank); other ranks get an empty vector.
    std::vector<std::string> gather(const std::string& mine, int tag) const;
    // Runs `work` on rank 0 first and on the other ranks after it (every rank calls this):
    // e.g. the impulse tables, which rank 0 tabulates into the shared cache folder and the
    // others then load instead of each tabulating them.
    template <class Work>
    void rank0_first(Work&& work) const {
        if (rank_ != 0) barrier();
        work();
        if (rank_ == 0) barrier();
    }
    // Prints "rank R of N (WORK): MESSAGE" and ends every rank with `code`.
    [[noreturn]] void abort(int code, const std::string& message) const;

  private:
    int rank_ = 0, size_ = 1;
    bool started_ = false;
    std::string work_;
};

}  // namespace freqlab
