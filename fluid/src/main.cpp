// sphfsi-fluid: the SPH fluid participant. Everything but physics is the shared participant runtime.
#include <memory>

#include "sphfsi/fluid/openmp_environment.hpp"
#include "sphfsi/fluid/sph_solver.hpp"
#include "sphfsi/protocol/participant.hpp"

int main(int argc, char** argv) {
    sphfsi::fluid::ensure_openmp_wait_policy(argv);
    return sphfsi::protocol::run_participant(argc, argv, std::make_unique<sphfsi::fluid::SphSolver>());
}
