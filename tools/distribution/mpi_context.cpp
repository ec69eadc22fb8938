#include "tools/distribution/mpi_context.h"

#include <mpi.h>

#include <cstdint>
#include <cstdlib>
#include <stdexcept>

namespace triadcal {
namespace {

struct JobState {
  bool active = false;  // MPI initialised by MpiSession
  int rank = 0, size = 1, local_size = 1;
};

JobState& State() {
  static JobState s;
  return s;
}

bool LaunchedByMpi() {
  for (const char* v : {"OMPI_COMM_WORLD_SIZE", "PMIX_RANK", "PMI_RANK", "PMI_SIZE"}) {
    if (std::getenv(v)) return true;
  }
  return false;
}

void Check(int rc, const char* what) {
  if (rc != MPI_SUCCESS) throw std::runtime_error(std::string("MPI: ") + what + " failed");
}

}  // namespace

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

std::vector<nlohmann::json> GatherJsonOnRoot(const nlohmann::json& mine) {
  const std::vector<std::uint8_t> bytes = nlohmann::json::to_cbor(mine);
  std::vector<nlohmann::json> out;
  for (const std::string& part : GatherOnRoot(std::string(bytes.begin(), bytes.end()))) {
    out.push_back(nlohmann::json::from_cbor(part));
  }
  return out;
}

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

}  // namespace triadcal
