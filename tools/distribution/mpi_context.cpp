#include "tools/distribution/mpi_context.h"

#if TRIADCAL_HAVE_MPI
#include <mpi.h>
#endif

#include <cstdint>
#include <cstdio>
#include <cstdlib>
#include <initializer_list>
#include <stdexcept>

namespace triadcal {
namespace {

bool LaunchedByMpi() {
  for (const char* v : {"OMPI_COMM_WORLD_SIZE", "PMIX_RANK", "PMI_RANK", "PMI_SIZE"}) {
    if (std::getenv(v)) return true;
  }
  return false;
}

#if TRIADCAL_HAVE_MPI
struct JobState {
  bool active = false;  // MPI initialised by MpiSession
  int rank = 0, size = 1, local_size = 1;
};

JobState& State() {
  static JobState s;
  return s;
}

void Check(int rc, const char* what) {
  if (rc != MPI_SUCCESS) throw std::runtime_error(std::string("MPI: ") + what + " failed");
}
#else
// The rank or size the launcher gave this process (0 when it gave none).
int LauncherNumber(std::initializer_list<const char*> names) {
  for (const char* v : names) {
    if (const char* text = std::getenv(v)) return std::atoi(text);
  }
  return 0;
}
#endif

}  // namespace

bool MpiBuilt() { return TRIADCAL_HAVE_MPI != 0; }

#if !TRIADCAL_HAVE_MPI
// Built without MPI (TRIADCAL_MPI=OFF): every process is a job of one rank. A
// launcher's job of several ranks is refused, as each rank would do all the
// work and write the same outputs; a launcher's single rank runs as usual.
MpiSession::MpiSession(int*, char***) {
  if (!LaunchedByMpi()) return;
  const int size = LauncherNumber({"OMPI_COMM_WORLD_SIZE", "PMI_SIZE", "PMIX_SIZE"});
  const int rank = LauncherNumber({"OMPI_COMM_WORLD_RANK", "PMIX_RANK", "PMI_RANK"});
  if (size > 1 || rank > 0) {
    std::fprintf(stderr,
                 "triadcal: error: this triadcal was built without MPI (TRIADCAL_MPI=OFF) and "
                 "cannot run as one of %d ranks; run it as one process, or split a batch with "
                 "--shard I/N (docs/scale-out.md)\n",
                 size > 1 ? size : rank + 1);
    std::exit(2);
  }
}
MpiSession::~MpiSession() = default;
int MpiRank() { return 0; }
int MpiSize() { return 1; }
int MpiLocalSize() { return 1; }
std::vector<std::string> GatherOnRoot(const std::string& mine) { return {mine}; }
void MpiAbortIfShared(int) {}
std::string BroadcastFromRoot(const std::string& text) { return text; }
#else
MpiSession::MpiSession(int* argc, char*** argv) {
  if (!LaunchedByMpi()) return;
  int provided = 0;
  // Threads of a rank (ParallelFor) never call MPI: funneled is enough.
  Check(MPI_Init_thread(argc, argv, MPI_THREAD_FUNNELED, &provided), "MPI_Init_thread");
  JobState& s = State();
  s.active = true;
  MPI_Comm_rank(MPI_COMM_WORLD, &s.rank);
  MPI_Comm_size(MPI_COMM_WORLD, &s.size);
  MPI_Comm node;
  MPI_Comm_split_type(MPI_COMM_WORLD, MPI_COMM_TYPE_SHARED, s.rank, MPI_INFO_NULL, &node);
  MPI_Comm_size(node, &s.local_size);
  MPI_Comm_free(&node);
}

MpiSession::~MpiSession() {
  if (State().active) MPI_Finalize();
  State() = JobState();
}

int MpiRank() { return State().rank; }
int MpiSize() { return State().size; }
int MpiLocalSize() { return State().local_size; }

std::vector<std::string> GatherOnRoot(const std::string& mine) {
  const JobState& s = State();
  if (!s.active || s.size == 1) return {mine};
  // Sizes first, then the bytes (MPI counts are int: at most 2 GiB per rank).
  if (mine.size() > static_cast<std::size_t>(INT32_MAX)) {
    throw std::runtime_error("MPI: more than 2 GiB to gather from one rank");
  }
  int n = static_cast<int>(mine.size());
  std::vector<int> sizes(s.rank == 0 ? s.size : 0);
  Check(MPI_Gather(&n, 1, MPI_INT, sizes.data(), 1, MPI_INT, 0, MPI_COMM_WORLD), "MPI_Gather");
  std::vector<int> offsets;
  std::string all;
  if (s.rank == 0) {
    offsets.resize(s.size);
    long long total = 0;
    for (int r = 0; r < s.size; ++r) {
      offsets[r] = static_cast<int>(total);
      total += sizes[r];
    }
    if (total > INT32_MAX) throw std::runtime_error("MPI: more than 2 GiB to gather");
    all.resize(static_cast<std::size_t>(total));
  }
  Check(MPI_Gatherv(mine.data(), n, MPI_CHAR, all.data(), sizes.data(), offsets.data(), MPI_CHAR, 0,
                    MPI_COMM_WORLD),
        "MPI_Gatherv");
  std::vector<std::string> out;
  if (s.rank == 0) {
    for (int r = 0; r < s.size; ++r) out.push_back(all.substr(offsets[r], sizes[r]));
  }
  return out;
}

#endif  // TRIADCAL_HAVE_MPI

std::vector<nlohmann::json> GatherJsonOnRoot(const nlohmann::json& mine) {
  const std::vector<std::uint8_t> bytes = nlohmann::json::to_cbor(mine);
  std::vector<nlohmann::json> out;
  for (const std::string& part : GatherOnRoot(std::string(bytes.begin(), bytes.end()))) {
    out.push_back(nlohmann::json::from_cbor(part));
  }
  return out;
}

#if TRIADCAL_HAVE_MPI
void MpiAbortIfShared(int code) {
  if (State().active && State().size > 1) MPI_Abort(MPI_COMM_WORLD, code);
}

std::string BroadcastFromRoot(const std::string& text) {
  const JobState& s = State();
  if (!s.active || s.size == 1) return text;
  int n = static_cast<int>(text.size());
  Check(MPI_Bcast(&n, 1, MPI_INT, 0, MPI_COMM_WORLD), "MPI_Bcast");
  std::string out = s.rank == 0 ? text : std::string(n, '\0');
  Check(MPI_Bcast(out.data(), n, MPI_CHAR, 0, MPI_COMM_WORLD), "MPI_Bcast");
  return out;
}
#endif  // TRIADCAL_HAVE_MPI

}  // namespace triadcal
