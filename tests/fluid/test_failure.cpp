// Failure is loud: an unstable configuration stops with SolverError("diverged") naming step, time,
// particle and quantity, instead of hanging or returning garbage.
#include <doctest/doctest.h>

#include <string>

#include "run_helpers.hpp"
#include "scenes.hpp"

using namespace fluid_test;

namespace {

std::string diverge(const Value& config, double window, std::uint32_t substeps) {
    auto s = start(config);
    sphfsi::protocol::Progress progress;
    for (int k = 0; k < 1000; ++k) {
        sphfsi::protocol::AdvanceRequest req;
        req.t = s->simulation().time();
        req.dt = window;
        req.substeps = substeps;
        try {
            s->advance(req, progress);
        } catch (const sphfsi::protocol::SolverError& e) {
            CHECK(e.code() == "diverged");
            return e.what();
        }
    }
    FAIL("no divergence detected");
    return "";
}

}  // namespace

TEST_SUITE("failure") {
    TEST_CASE("a step 50 times the stable one blows up and is reported") {
        // Stable step ~6e-5 s at this resolution; we force 3e-3 s.
        const std::string msg = diverge(wcsph(dam_break(0.1 / 16)), 3e-3, 1);
        MESSAGE(msg);
        CHECK(msg.find("step ") == 0);
        CHECK(msg.find(", t = ") != std::string::npos);
        CHECK(msg.find("particle ") != std::string::npos);
        CHECK(msg.find(" = ") != std::string::npos);
        CHECK(msg.find('(') != std::string::npos);
    }

    TEST_CASE("a stable step below the floor stops the run") {
        // The stable step starts at 1.87e-4 s and shrinks as the surge speeds up (CFL with c0 + |u|).
        const std::string msg = diverge(with(wcsph(dam_break(0.1 / 16)), {{"time.dt_min", 1.8e-4}}), 0.01, 0);
        MESSAGE(msg);
        CHECK(msg.find("time step") != std::string::npos);
        CHECK(msg.find("below the floor") != std::string::npos);
    }

    TEST_CASE("a density bound is enforced") {
        // Standard SPH with a very soft equation of state compresses far beyond 1 %.
        const std::string msg = diverge(with(wcsph(dam_break(0.1 / 16)), {{"pressure.model", "standard"},
                                                                           {"pressure.k", 20.0},
                                                                           {"failure.max_density_ratio", 1.01}}),
                                        0.01, 0);
        MESSAGE(msg);
        CHECK(msg.find("density = ") != std::string::npos);
        CHECK(msg.find("max_density_ratio") != std::string::npos);
    }
}
