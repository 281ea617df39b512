#pragma once
// OpenMP wait policy for a process that shares its cores. libgomp reads OMP_WAIT_POLICY / GOMP_SPINCOUNT
// once, when the library is loaded, so they cannot be changed from main(); a process started without
// either gets them set and re-executes itself (same pid) before any parallel region has run.
//
// Why: after a parallel region libgomp's idle threads spin (300000 iterations by default, effectively
// forever with OMP_WAIT_POLICY=active) before sleeping. The fluid shares two cores with the structure
// process, which runs while the fluid waits for it; spinning threads would steal its core. We choose a
// short spin (GOMP_SPINCOUNT=20000, a few tens of microseconds): long enough to bridge the gaps between
// the parallel loops of one time step (so threads do not sleep and re-wake inside a step), short enough
// that a waiting fluid yields its cores almost at once. A user who sets either variable is obeyed.
namespace sphfsi::fluid {

void ensure_openmp_wait_policy(char** argv);

}  // namespace sphfsi::fluid
