#include "jobs/mpi.hpp"

#include <cstdlib>

#ifdef FLEXFARM_WITH_MPI
#include <mpi.h>
#endif

namespace ff {

namespace {
MpiSession* g_session = nullptr;
bool launched_by_mpi() {
  return std::getenv("OMPI_COMM_WORLD_SIZE") || std::getenv("PMI_SIZE") || std::getenv("PMIX_RANK");
}
}  // namespace

MpiSession::MpiSession(int* argc, char*** argv) {
#ifdef FLEXFARM_WITH_MPI
  if (!launched_by_mpi()) return;
  int provided = 0;
  MPI_Init_thread(argc, argv, MPI_THREAD_FUNNELED, &provided);
  MPI_Comm_rank(MPI_COMM_WORLD, &rank_);
  MPI_Comm_size(MPI_COMM_WORLD, &size_);
  active_ = true;
#else
  (void)argc;
  (void)argv;
#endif
}

MpiSession::~MpiSession() {
#ifdef FLEXFARM_WITH_MPI
  if (active_) MPI_Finalize();
#endif
}

void MpiSession::barrier() const {
#ifdef FLEXFARM_WITH_MPI
  if (active_) MPI_Barrier(MPI_COMM_WORLD);
#endif
}

bool MpiSession::any(bool flag) const {
#ifdef FLEXFARM_WITH_MPI
  if (active_) {
    int in = flag ? 1 : 0, out = 0;
    MPI_Allreduce(&in, &out, 1, MPI_INT, MPI_LOR, MPI_COMM_WORLD);
    return out != 0;
  }
#endif
  return flag;
}

MpiSession& mpi() {
  static MpiSession single;
  return g_session ? *g_session : single;
}

void set_mpi(MpiSession* session) { g_session = session; }

}  // namespace ff
