// MPI, when the binary was built with it and started by mpirun/srun; otherwise one rank of one.
#pragma once

namespace ff {

class MpiSession {
 public:
  // Initialises MPI only when a launcher started this process (OMPI_COMM_WORLD_SIZE, PMI_SIZE or
  // PMIX_RANK in the environment), so a plain `flexfarm run` never needs an MPI runtime.
  MpiSession(int* argc, char*** argv);
  MpiSession() = default;  // one rank of one
  ~MpiSession();
  MpiSession(const MpiSession&) = delete;
  MpiSession& operator=(const MpiSession&) = delete;

  int rank() const { return rank_; }
  int size() const { return size_; }
  void barrier() const;
  // Logical OR of `flag` over all ranks.
  bool any(bool flag) const;

 private:
  int rank_ = 0;
  int size_ = 1;
  bool active_ = false;
};

// The process-wide session (set up by main).
MpiSession& mpi();
void set_mpi(MpiSession* session);

}  // namespace ff
