#include "sphfsi/fluid/openmp_environment.hpp"

#include <cstdlib>
#include <unistd.h>

namespace sphfsi::fluid {

void ensure_openmp_wait_policy(char** argv) {
    if (std::getenv("OMP_WAIT_POLICY") || std::getenv("GOMP_SPINCOUNT") || std::getenv("SPHFSI_OMP_POLICY_SET")) return;
    ::setenv("GOMP_SPINCOUNT", "20000", 1);
    ::setenv("SPHFSI_OMP_POLICY_SET", "1", 1);  // guards against a loop if exec keeps failing
    ::execv("/proc/self/exe", argv);
    // exec failed (no /proc): carry on with the default policy rather than not run at all.
}

}  // namespace sphfsi::fluid
