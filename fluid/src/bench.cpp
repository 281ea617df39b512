// sphfsi-fluid-bench: particle-steps per second for the dam break (the thesis's 0.1 m x 0.2 m column in a
// 0.5 m tank) at about 10k, 40k and 160k fluid particles, 1 and 2 threads, for each pressure model.
// Set-up as in DualSPHysics's dam-break benchmarks: Wendland kernel, h = 1.41 dp, artificial viscosity
// (alpha = 0.02), Adami walls, symplectic (semi-implicit) Euler; WCSPH with Fourtakas density diffusion;
// PCISPH with summation densities (eta = 1 %); standard SPH as the thesis runs it (and the validation
// sweeps call it): k = 1000 m^2/s^2, summation densities. A model named with
// "+kgc" (wcsph+kgc, standard+kgc) runs with pressure.kernel_correction = true, to time the correction.
//
//   sphfsi-fluid-bench [--sizes 10k,40k,160k] [--threads 1,2] [--models wcsph,pcisph,standard] [--steps N]
//
// The default (--sizes 10k, 100 steps) takes a few seconds. Each run first takes 20 warm-up steps (the
// column starts to fall), then times --steps adaptive steps. Particles counted: all (fluid + wall), as
// DualSPHysics reports them. "threads" is the count the simulation uses (one below 4,000 particles; 0 asks
// for every core). "bytes/part" is the solver's own count of its arrays per particle; "peak_rss/part" the
// whole process's peak resident set (VmHWM: code and runtime included, so it falls with size) over the
// particles, and "peak_rss_kB" that peak itself. The peak is reset before each setup, so several setups in
// one process each print their own; where the kernel refuses the reset, setups after the first print n/a.
#include <chrono>
#include <cmath>
#include <cstdio>
#include <cstdlib>
#include <fstream>
#include <sstream>
#include <string>
#include <vector>

#include <malloc.h>
#include <omp.h>

#include "sphfsi/fluid/openmp_environment.hpp"
#include "sphfsi/fluid/sph_solver.hpp"

using sphfsi::Value;

namespace {

std::vector<std::string> split(const std::string& s) {
    std::vector<std::string> out;
    std::stringstream ss(s);
    std::string item;
    while (std::getline(ss, item, ',')) out.push_back(item);
    return out;
}

Value scene(double dp, const std::string& name, int threads) {
    const bool corrected = name.ends_with("+kgc");
    const std::string model = corrected ? name.substr(0, name.size() - 4) : name;
    Value f;
    f.make_table();
    auto set = [&](const char* k, Value v) { sphfsi::set_path(f, k, std::move(v)); };
    set("dp", dp);
    set("threads", threads);
    set("h_over_dp", 1.41);
    set("kernel", "wendland");
    set("tank.width", 0.5);
    set("tank.height", 0.3);
    set("viscosity.model", "artificial");
    set("viscosity.alpha", 0.02);
    set("boundary.model", "adami");
    set("time.integrator", "symplectic_euler");
    set("pressure.model", model);
    set("pressure.kernel_correction", corrected);
    const bool summed = model == "pcisph" || model == "standard";
    set("density.method", summed ? "summation" : "continuity");
    set("density.diffusion", summed ? "none" : "fourtakas");
    Value::Table block;
    block["x0"] = 0.0;
    block["y0"] = 0.0;
    block["width"] = 0.1;
    block["height"] = 0.2;
    f.as_table_mut()["water"] = Value(Value::Array{Value(std::move(block))});
    return f;
}

double fluid_count_to_dp(double n) { return std::sqrt(0.1 * 0.2 / n); }

// The process's own peak resident set (VmHWM), in bytes. Not getrusage's ru_maxrss: that carries the
// launching process's resident set across fork and exec (a Python launcher adds about 10 MiB).
double peak_resident_bytes() {
    std::ifstream status("/proc/self/status");
    std::string line;
    while (std::getline(status, line))
        if (line.rfind("VmHWM:", 0) == 0) return std::atof(line.c_str() + 6) * 1024.0;
    return 0.0;
}

// Starts a new peak: VmHWM is the process's life-time peak, so without this every setup after the first
// would print the largest earlier one's. Writing "5" to clear_refs sets it to the current resident set
// (Linux >= 4.0); the freed memory the allocator still holds from the setup before is handed back first,
// or it would count in this one's peak. False where the write is refused.
bool reset_peak_resident() {
    malloc_trim(0);
    std::ofstream clear("/proc/self/clear_refs");
    clear << "5" << std::flush;
    return static_cast<bool>(clear);
}

}  // namespace

int main(int argc, char** argv) {
    sphfsi::fluid::ensure_openmp_wait_policy(argv);
    std::vector<std::string> sizes{"10k"}, threads{"1", "2"}, models{"wcsph", "pcisph", "standard"};
    int steps = 100;
    for (int i = 1; i < argc; i += 2) {  // options come in pairs; anything else (--help too) prints the usage
        const std::string a = argv[i], v = i + 1 < argc ? argv[i + 1] : "";
        if (!v.empty() && a == "--sizes") sizes = split(v);
        else if (!v.empty() && a == "--threads") threads = split(v);
        else if (!v.empty() && a == "--models") models = split(v);
        else if (!v.empty() && a == "--steps" && std::atoi(v.c_str()) > 0) steps = std::atoi(v.c_str());
        else {
            const bool help = a == "--help" || a == "-h";
            std::fprintf(help ? stdout : stderr, "usage: %s [--sizes 10k,40k,160k] [--threads 1,2] [--models wcsph,pcisph,standard,wcsph+kgc,standard+kgc] [--steps N > 0]\n", argv[0]);
            return help ? 0 : 2;
        }
    }
    std::printf("%-9s %7s %9s %9s %7s %7s %9s %14s %10s %10s %10s\n", "model", "threads", "fluid", "particles", "steps",
                "iters", "wall_s", "particle-steps/s", "bytes/part", "peak_rss/part", "peak_rss_kB");
    bool first_setup = true, peak_valid = true;
    for (const auto& size : sizes) {
        const double n = std::atof(size.c_str()) * (size.back() == 'k' ? 1e3 : size.back() == 'M' ? 1e6 : 1.0);
        const double dp = fluid_count_to_dp(n);
        for (const auto& model : models)
            for (const auto& th : threads) {
                // The first setup's peak is valid without a reset: nothing before it but start-up.
                peak_valid = reset_peak_resident() || (first_setup && peak_valid);
                first_setup = false;
                sphfsi::fluid::SphSolver solver;
                sphfsi::protocol::InitRequest init;
                init.config = scene(dp, model, std::atoi(th.c_str()));
                solver.init(init);
                auto& sim = solver.simulation();
                sphfsi::protocol::Progress progress;
                auto advance_steps = [&](int k, unsigned& iters) {
                    int taken = 0;
                    while (taken < k) {
                        sphfsi::protocol::AdvanceRequest req;
                        req.t = sim.time();
                        req.dt = sim.stable_dt();  // one adaptive step per window
                        const auto r = solver.advance(req, progress);
                        taken += static_cast<int>(r.substeps);
                        iters += r.solver_iterations;
                    }
                    return taken;
                };
                unsigned iters = 0;
                advance_steps(20, iters);
                iters = 0;
                const auto t0 = std::chrono::steady_clock::now();
                const int taken = advance_steps(steps, iters);
                const double wall = std::chrono::duration<double>(std::chrono::steady_clock::now() - t0).count();
                const double np = static_cast<double>(sim.particles().size());
                const double peak = peak_resident_bytes();
                char per_particle[32] = "n/a", kib[32] = "n/a";
                if (peak_valid) {
                    std::snprintf(per_particle, sizeof per_particle, "%.0f", peak / np);
                    std::snprintf(kib, sizeof kib, "%.0f", peak / 1024.0);
                }
                std::printf("%-9s %7d %9zu %9zu %7d %7u %9.3f %14.3e %10.0f %10s %10s\n", model.c_str(), sim.threads(),
                            sim.fluid_count(), sim.particles().size(), taken, iters, wall, np * taken / wall,
                            static_cast<double>(sim.memory_bytes()) / np, per_particle, kib);
                std::fflush(stdout);
            }
    }
    return 0;
}
