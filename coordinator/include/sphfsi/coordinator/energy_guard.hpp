#pragma once
// Stops a coupled run whose energy is not physics (docs/coupling.md, "Automatic stop"). Two checks after
// every recorded window, both against the fluid's mechanical energy E_f after the first window:
//  - the interface balance: energy created at the interface, F . (du_s - du_f) summed since t0, beyond
//    coupling.max_created_energy x E_f (names the vertex that created the most);
//  - the total: fluid (kinetic + potential) plus structure (kinetic + strain) mechanical energy risen above
//    its value after the first window by more than coupling.max_energy_gain x E_f. Without external work
//    the pair can only lose energy; this also sees energy that enters through the wall velocity, which the
//    interface balance does not (an explicit scheme without a predictor).
// The running sums live in InterfaceState, so a resumed run continues them.
#include <cstdint>
#include <string>

#include "sphfsi/coordinator/coupling.hpp"
#include "sphfsi/coordinator/interface_energy.hpp"
#include "sphfsi/coordinator/session.hpp"

namespace sphfsi::coordinator {

struct EnergyLimits {
    double max_created = 1.0;     // coupling.max_created_energy (0: no check)
    double max_gain = 0.05;       // coupling.max_energy_gain (0: no check)
    bool external_work = false;   // the scene does work on the pair (wind, a moving lid, a body force along a
                                  // periodic axis): no total check
};

// Adds the window to the sums in `s` and throws std::runtime_error("coupling diverged: ...") when a limit is
// passed. A participant that does not report its energies in ADVANCED.stats gets no total check. Returns a
// warning to log, once, when the fluid's energy after the first window is not positive and the checks are
// off for the run (empty otherwise).
std::string account_energy(const EnergyLimits& limits, std::uint64_t window, double t, const WindowOutcome& o,
                           const InterfaceWork& work, InterfaceState& s);

}  // namespace sphfsi::coordinator
