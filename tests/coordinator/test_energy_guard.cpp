// The total-energy check of coordinator/src/energy_guard.cpp: its baseline is the fluid's plus the
// structure's mechanical energy less the structure's own load work after the first window, which can be
// zero or negative (a structure whose scene loads did more work than the pair holds). The check must then
// still run: it used to read a baseline <= 0 as "not known yet" and re-take it every window, so it never
// ran (a review, 2026-11-27).
#include <doctest/doctest.h>

#include <stdexcept>
#include <string>

#include "sphfsi/coordinator/energy_guard.hpp"

using namespace sphfsi;
using namespace sphfsi::coordinator;

namespace {

// A window in which the fluid holds `fluid` J/m (all kinetic) and the structure `structure` J/m, its scene
// loads having done `load_work` J/m on it in all (no work through the interface).
WindowOutcome window(double fluid, double structure, double load_work) {
    WindowOutcome o;
    o.fluid.reply.stats = Value(Value::Table{{"kinetic_energy", Value(fluid)}, {"potential_energy", Value(0.0)}});
    o.structure.reply.stats = Value(Value::Table{{"kinetic_energy", Value(structure)}, {"strain_energy", Value(0.0)},
                                                 {"external_work", Value(load_work)}});
    return o;
}

}  // namespace

TEST_SUITE("energy_guard") {
    TEST_CASE("a baseline of zero or below is a baseline: energy gained after it stops the run") {
        const EnergyLimits limits;  // max_gain 0.05 of the fluid's energy
        InterfaceState s;
        // First window: fluid 10 J/m, structure 2 J/m after its loads did 12 J/m: the baseline is 0.
        account_energy(limits, 1, 0.01, window(10.0, 2.0, 12.0), InterfaceWork{}, s);
        CHECK(s.total_energy == 0.0);
        // Nothing gained: no stop. Then 1 J/m from nowhere (0.1 of the fluid's 10 J/m, over the 0.05 allowed).
        account_energy(limits, 2, 0.02, window(10.0, 2.0, 12.0), InterfaceWork{}, s);
        std::string what;
        try {
            account_energy(limits, 3, 0.03, window(11.0, 2.0, 12.0), InterfaceWork{}, s);
        } catch (const std::runtime_error& e) {
            what = e.what();
        }
        MESSAGE(what);
        CHECK(what.find("coupling diverged: window 3") != std::string::npos);
        // Below zero too: the loads did 13 J/m, the pair holds 12, so the baseline is -1 J/m.
        InterfaceState n;
        account_energy(limits, 1, 0.01, window(10.0, 2.0, 13.0), InterfaceWork{}, n);
        CHECK(n.total_energy == -1.0);
        account_energy(limits, 2, 0.02, window(10.0, 2.0, 13.0), InterfaceWork{}, n);
        CHECK_THROWS_WITH_AS(account_energy(limits, 3, 0.03, window(11.0, 2.0, 13.0), InterfaceWork{}, n),
                             doctest::Contains("coupling diverged: window 3"), std::runtime_error);
    }

    TEST_CASE("the fluid's yardstick is the first window's; not positive, the checks are off and say so once") {
        const EnergyLimits limits;
        {  // Taken once: a later window's larger energy does not replace it.
            InterfaceState s;
            CHECK(account_energy(limits, 1, 0.01, window(10.0, 2.0, 0.0), InterfaceWork{}, s).empty());
            CHECK(account_energy(limits, 2, 0.02, window(10.4, 2.0, 0.0), InterfaceWork{}, s).empty());
            CHECK(s.fluid_energy == 10.0);
        }
        // Potential energy from the origin can be negative: no scale, and the checks must not wake up later with
        // a yardstick from some window that happened to be positive (it was re-taken until it was).
        InterfaceState s;
        const std::string said = account_energy(limits, 1, 0.01, window(-4.0, 2.0, 0.0), InterfaceWork{}, s);
        CHECK(said.find("-4 J/m, not positive") != std::string::npos);
        CHECK(account_energy(limits, 2, 0.02, window(5.0, 2.0, 0.0), InterfaceWork{}, s).empty());
        CHECK(account_energy(limits, 3, 0.03, window(50.0, 2.0, 0.0), InterfaceWork{}, s).empty());  // no stop
    }

    TEST_CASE("a structure that reports its energies but not external_work leaves the gain unchecked, said once") {
        // Its own weight may be doing work the balance cannot take out: a foreign structure under gravity that
        // reported kinetic and strain energy alone was stopped as diverged in its 4th window (2026-11-28).
        const EnergyLimits limits;
        auto without_work = [](double fluid, double structure) {
            WindowOutcome o = window(fluid, structure, 0.0);
            o.structure.reply.stats = Value(Value::Table{{"kinetic_energy", Value(structure)}, {"strain_energy", Value(0.0)}});
            return o;
        };
        InterfaceState s;
        const std::string said = account_energy(limits, 1, 0.01, without_work(10.0, 2.0), InterfaceWork{}, s);
        CHECK(said.find("not external_work") != std::string::npos);
        CHECK(account_energy(limits, 2, 0.02, without_work(10.0, 40.0), InterfaceWork{}, s).empty());  // no stop
        CHECK(account_energy(limits, 3, 0.03, without_work(10.0, 80.0), InterfaceWork{}, s).empty());  // said once
        // With external_work the same gain stops the run.
        InterfaceState t;
        account_energy(limits, 1, 0.01, window(10.0, 2.0, 0.0), InterfaceWork{}, t);
        CHECK_THROWS_WITH_AS(account_energy(limits, 2, 0.02, window(10.0, 40.0, 0.0), InterfaceWork{}, t),
                             doctest::Contains("coupling diverged: window 2"), std::runtime_error);
    }
}
