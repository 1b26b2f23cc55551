// The fleet on MPI (`mpirun -np N lmcal fleet ROOT`): dynamic master-worker. Rank 0 hands out
// one set at a time to whichever rank asks (sets differ tenfold in cost: no static split) and
// calibrates sets itself on a thread of its own meanwhile; each worker writes its set's files
// whole or not at all and sends the set's record back; rank 0 gathers them and writes the
// summary. Built only when CMake finds MPI (LMCAL_WITH_MPI).
//
// Trap: rank 0 polls for requests (MPI_Iprobe, then a millisecond's sleep) rather than
// blocking: Open MPI's blocking receive spins and would take a core from the calibrations.
#pragma once

#include <cstddef>

#include "lmcal/fleet/fleet.hpp"

namespace lmcal::cli {

// Whether this process was started by an MPI launcher (mpirun, srun with PMI): only then is
// MPI initialised, so a plain `lmcal fleet` never touches it.
bool launched_by_mpi();

// MPI_Init_thread on construction, MPI_Finalize on destruction.
class MpiSession {
 public:
  MpiSession();
  ~MpiSession();
  MpiSession(const MpiSession&) = delete;
  MpiSession& operator=(const MpiSession&) = delete;
  int rank() const { return rank_; }
  int size() const { return size_; }

 private:
  int rank_ = 0, size_ = 1;
};

// This shard's sets over every rank of the session. On rank 0 the run holds every record; on
// the others, none. An error on any rank (outputs that could not be written) stops the
// distribution and is rethrown on rank 0.
FleetRun run_fleet_mpi(const MpiSession& mpi, const Fleet& fleet, const FleetOptions& options,
                       const FleetProgress& progress);

}  // namespace lmcal::cli
