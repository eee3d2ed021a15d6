#include "cluster.h"

#include <chrono>
#include <climits>
#include <cstdio>
#include <cstdlib>
#include <thread>

#include "base/error.h"

#ifdef FREQLAB_HAS_MPI
// The C API only (OpenMPI's deprecated C++ bindings live in another library).
#define OMPI_SKIP_MPICXX 1
#define MPICH_SKIP_MPICXX 1
#include <mpi.h>
#endif

namespace freqlab {

WorkPart parse_work_part(const std::string& text, const std::string& flag) {
    WorkPart p;
    char tail = 0;
    if (std::sscanf(text.c_str(), "%d/%d%c", &p.index, &p.count, &tail) != 2 || p.count < 1 ||
        p.index < 0 || p.index >= p.count)
        throw Error(flag, text, "expected I/N with 0 <= I < N (this part and the number of parts)");
    return p;
}

std::vector<int> round_robin_items(int first, int last, WorkPart part) {
    std::vector<int> items;
    for (int i = first + part.index; i < last; i += part.count) items.push_back(i);
    return items;
}

std::pair<int, int> contiguous_items(int first, int last, WorkPart part) {
    const long n = long(last) - first;
    const int a = first + int(n * part.index / part.count);
    const int b = first + int(n * (part.index + 1) / part.count);
    return {a, b};
}

std::string describe_items(const std::vector<int>& items) {
    std::string s;
    for (size_t i = 0; i < items.size() && i < 6; ++i)
        s += (i ? ", " : "") + std::to_string(items[i]);
    if (items.size() > 6) s += ", ... (" + std::to_string(items.size()) + " in all)";
    return items.empty() ? "nothing" : s;
}

Cluster& Cluster::world() {
    static Cluster cluster;
    return cluster;
}

namespace {
// Set by mpirun / srun / hydra in every process they start.
bool launched_by_mpi() {
    for (const char* v : {"OMPI_COMM_WORLD_SIZE", "PMI_SIZE", "PMIX_RANK", "MPI_LOCALNRANKS"})
        if (std::getenv(v)) return true;
    return false;
}
}  // namespace

void Cluster::start(int* argc, char*** argv) {
#ifdef FREQLAB_HAS_MPI
    if (!launched_by_mpi()) return;
    // Rank 0 receives frames on a second thread while its main thread renders: the two never
    // call MPI at the same time, which MPI_THREAD_SERIALIZED allows.
    int provided = 0;
    MPI_Init_thread(argc, argv, MPI_THREAD_SERIALIZED, &provided);
    started_ = true;
    MPI_Comm_rank(MPI_COMM_WORLD, &rank_);
    MPI_Comm_size(MPI_COMM_WORLD, &size_);
    if (provided < MPI_THREAD_SERIALIZED)
        abort(1, "this MPI library does not provide MPI_THREAD_SERIALIZED");
#else
    (void)argc, (void)argv;
    if (launched_by_mpi() && std::getenv("OMPI_COMM_WORLD_RANK") &&
        std::atoi(std::getenv("OMPI_COMM_WORLD_RANK")) != 0) {
        // Every rank would do the whole work and write the same files: refuse loudly instead.
        std::fprintf(stderr,
                     "error: freqlab was built without MPI (FREQLAB_MPI=OFF or libopenmpi-dev "
                     "missing) but started by mpirun: run it as one process\n");
        std::exit(1);
    }
#endif
}

void Cluster::finish() {
#ifdef FREQLAB_HAS_MPI
    // MPI_Finalize synchronises busily: ranks done early would spin there while rank 0 still
    // writes; they wait here asleep instead.
    if (started_) barrier();
    if (started_) MPI_Finalize();
    started_ = false;
#endif
}

#ifdef FREQLAB_HAS_MPI
namespace {
void check_count(size_t n) {
    if (n > size_t(INT_MAX))
        throw Error("MPI", "message", "a message of " + std::to_string(n) + " bytes (over 2 GB)");
}

// MPI_Probe busy-polls: a rank waiting on it (rank 0's frame receiver, a rank at a barrier)
// took a whole core from the ranks still rendering (2 ranks on 2 cores rendered 1.15x faster
// than 1, not 2x). Waiting here sleeps between non-blocking probes instead.
MPI_Status probe_sleeping(int source, int tag) {
    MPI_Status status;
    for (int flag = 0;;) {
        MPI_Iprobe(source, tag, MPI_COMM_WORLD, &flag, &status);
        if (flag) return status;
        std::this_thread::sleep_for(std::chrono::milliseconds(1));
    }
}

constexpr int kBarrierTag = 32000;  // MPI guarantees tags up to 32767
}  // namespace

void Cluster::send(int to, int tag, const std::string& bytes) const {
    check_count(bytes.size());
    MPI_Send(bytes.data(), int(bytes.size()), MPI_BYTE, to, tag, MPI_COMM_WORLD);
}

std::pair<int, std::string> Cluster::receive_any(int tag) const {
    const MPI_Status status = probe_sleeping(MPI_ANY_SOURCE, tag);
    int count = 0;
    MPI_Get_count(&status, MPI_BYTE, &count);
    std::string bytes(size_t(count), '\0');
    MPI_Recv(bytes.data(), count, MPI_BYTE, status.MPI_SOURCE, tag, MPI_COMM_WORLD,
             MPI_STATUS_IGNORE);
    return {status.MPI_SOURCE, std::move(bytes)};
}

std::string Cluster::receive(int from, int tag) const {
    const MPI_Status status = probe_sleeping(from, tag);
    int count = 0;
    MPI_Get_count(&status, MPI_BYTE, &count);
    std::string bytes(size_t(count), '\0');
    MPI_Recv(bytes.data(), count, MPI_BYTE, from, tag, MPI_COMM_WORLD, MPI_STATUS_IGNORE);
    return bytes;
}

// Every rank reports to rank 0, which then releases them all (sleeping while it waits, unlike
// MPI_Barrier).
void Cluster::barrier() const {
    if (!started_ || size_ == 1) return;
    if (rank_ == 0) {
        for (int r = 1; r < size_; ++r) receive(r, kBarrierTag);
        for (int r = 1; r < size_; ++r) send(r, kBarrierTag, "");
    } else {
        send(0, kBarrierTag, "");
        receive(0, kBarrierTag);
    }
}

[[noreturn]] void Cluster::abort(int code, const std::string& message) const {
    std::fprintf(stderr, "rank %d of %d (%s): %s\n", rank_, size_,
                 work_.empty() ? "before its work" : work_.c_str(), message.c_str());
    std::fflush(stderr);
    if (started_) MPI_Abort(MPI_COMM_WORLD, code);
    std::exit(code);
}
#else
void Cluster::send(int, int, const std::string&) const {
    throw Error("MPI", "send", "freqlab was built without MPI");
}
std::pair<int, std::string> Cluster::receive_any(int) const {
    throw Error("MPI", "receive", "freqlab was built without MPI");
}
std::string Cluster::receive(int, int) const {
    throw Error("MPI", "receive", "freqlab was built without MPI");
}
void Cluster::barrier() const {}
[[noreturn]] void Cluster::abort(int code, const std::string& message) const {
    std::fprintf(stderr, "%s\n", message.c_str());
    std::exit(code);
}
#endif

std::vector<std::string> Cluster::gather(const std::string& mine, int tag) const {
    std::vector<std::string> all;
    if (rank_ != 0) {
        send(0, tag, mine);
        return all;
    }
    all.resize(size_t(size_));
    all[0] = mine;
    for (int r = 1; r < size_; ++r) all[size_t(r)] = receive(r, tag);
    return all;
}

}  // namespace freqlab
