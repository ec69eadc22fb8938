// The MPI job this process belongs to, for the commands that split their work
// over ranks (montecarlo, batch). Every other file stays free of MPI.
//
// MPI is initialised only when an MPI launcher started the process (mpirun,
// mpiexec or srun set OMPI_COMM_WORLD_SIZE, PMIX_RANK or PMI_RANK); a plain
// `triadcal ...` is a job of one rank and never touches MPI, so commands run
// without MPI's start-up cost and on machines where the MPI runtime cannot
// start (no network interface, a container).
#pragma once

#include <string>
#include <vector>

#include <nlohmann/json.hpp>

namespace triadcal {

// Whether this build has MPI (CMake option TRIADCAL_MPI). Without it every
// process is a job of one rank, and a launcher's job of several ranks is
// refused by MpiSession (exit 2, one line on stderr).
bool MpiBuilt();

class MpiSession {
 public:
  // Initialises MPI when launched by an MPI launcher; finalises on destruction.
  MpiSession(int* argc, char*** argv);
  ~MpiSession();
  MpiSession(const MpiSession&) = delete;
  MpiSession& operator=(const MpiSession&) = delete;
};

// This process's place in the job: rank 0 of 1 without a launcher.
int MpiRank();
int MpiSize();
inline bool MpiRoot() { return MpiRank() == 0; }

// Ranks of the job on this machine (1 without a launcher): the cores a rank
// may use are the machine's divided by this.
int MpiLocalSize();

// Every rank passes its bytes; rank 0 receives them all in rank order, the
// other ranks an empty vector. Collective: every rank must call it.
std::vector<std::string> GatherOnRoot(const std::string& mine);

// GatherOnRoot of JSON values, sent as CBOR (binary; doubles travel as their
// 8 bytes, so they arrive bit for bit). Rank 0 gets every rank's value in
// rank order, the others an empty vector. Collective.
std::vector<nlohmann::json> GatherJsonOnRoot(const nlohmann::json& mine);

// Ends the whole job when it has more than one rank (a rank that failed alone
// would leave the others waiting in a collective); returns otherwise.
void MpiAbortIfShared(int code);

// Rank 0's `text` on every rank. Collective.
std::string BroadcastFromRoot(const std::string& text);

}  // namespace triadcal
