// sphfsi-structure-bench: wall-clock cost of one implicit step of the structure solver.
//
// Case: steel cantilever strip (L = 1 m, t = 10 mm, b = 1 m) with n elements, generalized-alpha
// (rho_inf = 0.9), step dt = T1 / 200, under a step tip load P L^2 / EI = 2 (tip rotation ~45-80 deg,
// so the co-rotational Newton iterations do real work). Each configuration takes one warm-up step (it
// builds the linear factorization), then `repeats` timed blocks of `steps` steps; the median block time
// divided by `steps` is reported, with the fastest and slowest block for spread.
//
// Usage: sphfsi-structure-bench [--repeats N] [--steps N] [--quick]
#include <algorithm>
#include <chrono>
#include <cstdio>
#include <cstring>
#include <numbers>
#include <string>
#include <vector>

#include "sphfsi/structure/frame_dynamics.hpp"
#include "sphfsi/structure/heap.hpp"

using namespace sphfsi;
using namespace sphfsi::structure;

namespace {

using Clock = std::chrono::steady_clock;

double seconds_since(Clock::time_point start) {
    return std::chrono::duration<double>(Clock::now() - start).count();
}

Value scene(int n, const char* formulation) {
    const double E = 2.1e11, t = 0.01, EI = E * t * t * t / 12.0;
    auto vec = [](double x, double y) { return Value(Value::Array{Value(x), Value(y)}); };
    Value::Table load{{"at", vec(1.0, 0.0)}, {"force", vec(0.0, -2.0 * EI)}};
    return Value(Value::Table{
        {"formulation", Value(formulation)},
        {"material", Value(Value::Table{{"E", Value(E)}, {"rho", Value(7850.0)}})},
        {"section", Value(Value::Table{{"thickness", Value(t)}})},
        {"members", Value(Value::Array{Value(Value::Table{{"start", vec(0, 0)}, {"end", vec(1, 0)}, {"n_elements", Value(n)}})})},
        {"supports", Value(Value::Array{Value(Value::Table{{"at", vec(0, 0)}, {"type", Value("clamped")}})})},
        {"point_loads", Value(Value::Array{Value(std::move(load))})},
    });
}

struct Result {
    double init_s = 0, first_step_s = 0, median_s = 0, min_s = 0, max_s = 0, iterations_per_step = 0;
    int factorizations = 0;
};

Result measure(int n, const char* formulation, int repeats, int steps) {
    Result r;
    auto start = Clock::now();
    FrameDynamics f(StructureConfig::from_value(scene(n, formulation)));
    r.init_s = seconds_since(start);
    const double dt = 2 * std::numbers::pi / f.modes().omega(0) / 200.0;

    start = Clock::now();
    f.step(dt, Vector());
    r.first_step_s = seconds_since(start);

    std::vector<double> per_step;
    long iterations = 0;
    for (int k = 0; k < repeats; ++k) {
        start = Clock::now();
        for (int s = 0; s < steps; ++s) iterations += f.step(dt, Vector()).iterations;
        per_step.push_back(seconds_since(start) / steps);
    }
    std::sort(per_step.begin(), per_step.end());
    const std::size_t m = per_step.size();
    r.median_s = m % 2 ? per_step[m / 2] : 0.5 * (per_step[m / 2 - 1] + per_step[m / 2]);
    r.min_s = per_step.front();
    r.max_s = per_step.back();
    r.iterations_per_step = static_cast<double>(iterations) / (repeats * steps);
    r.factorizations = f.factorizations();
    return r;
}

}  // namespace

int main(int argc, char** argv) {
    sphfsi::structure::keep_freed_memory();  // as sphfsi-structure does
    int repeats = 7, steps = 20;
    std::vector<int> sizes{10, 100, 1000};
    for (int i = 1; i < argc; ++i) {
        if (!std::strcmp(argv[i], "--repeats") && i + 1 < argc) {
            repeats = std::max(1, std::atoi(argv[++i]));
        } else if (!std::strcmp(argv[i], "--steps") && i + 1 < argc) {
            steps = std::max(1, std::atoi(argv[++i]));
        } else if (!std::strcmp(argv[i], "--quick")) {  // smoke test: small sizes, few repeats
            repeats = 3;
            steps = 5;
            sizes = {10, 100};
        } else {
            std::fprintf(stderr, "usage: %s [--repeats N] [--steps N] [--quick]\n", argv[0]);
            return 2;
        }
    }
    std::printf("| elements | formulation | step, median [ms] | min - max [ms] | Newton its/step | first step [ms] | "
                "factorizations | setup incl. modes [ms] |\n|---|---|---|---|---|---|---|---|\n");
    for (const char* formulation : {"linear", "corotational"}) {
        for (int n : sizes) {
            const Result r = measure(n, formulation, repeats, steps);
            std::printf("| %d | %s | %.4f | %.4f - %.4f | %.2f | %.4f | %d | %.1f |\n", n, formulation, 1e3 * r.median_s,
                        1e3 * r.min_s, 1e3 * r.max_s, r.iterations_per_step, 1e3 * r.first_step_s, r.factorizations,
                        1e3 * r.init_s);
            std::fflush(stdout);
        }
    }
    std::printf("\n%d repeats x %d steps per configuration; dt = T1/200, generalized-alpha rho_inf = 0.9.\n", repeats,
                steps);
    return 0;
}
