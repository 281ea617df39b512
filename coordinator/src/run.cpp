#include "sphfsi/coordinator/run.hpp"

#include <sys/resource.h>

#include <algorithm>
#include <chrono>
#include <cmath>
#include <csignal>
#include <exception>
#include <fstream>
#include <iostream>
#include <limits>
#include <optional>
#include <random>
#include <sstream>

#include "sphfsi/coordinator/checkpoint.hpp"
#include "sphfsi/coordinator/coupling.hpp"
#include "sphfsi/coordinator/dir_lock.hpp"
#include "sphfsi/coordinator/energy_guard.hpp"
#include "sphfsi/coordinator/git_revision.hpp"
#include "sphfsi/coordinator/hub.hpp"
#include "sphfsi/coordinator/interface_energy.hpp"
#include "sphfsi/coordinator/launcher.hpp"
#include "sphfsi/coordinator/progress.hpp"
#include "sphfsi/coordinator/recorder.hpp"
#include "sphfsi/coordinator/scene.hpp"
#include "sphfsi/coordinator/scene_warnings.hpp"
#include "sphfsi/fluid/schema.hpp"
#include "sphfsi/coordinator/version.hpp"
#include "sphfsi/coordinator/watchpoints.hpp"

namespace sphfsi::coordinator {
using namespace sphfsi::protocol;
using Clock = std::chrono::steady_clock;

namespace {
void on_signal(int) { g_interrupted = 1; }

std::string random_token() {
    std::random_device rd;  // /dev/urandom on Linux
    static const char* hex = "0123456789abcdef";
    std::string t;
    for (int i = 0; i < 32; ++i) t += hex[rd() % 16];
    return t;
}

bool at_rest_undeformed(const InterfaceState& s) {
    auto zero = [](const F64Array& a) { return std::all_of(a.values.begin(), a.values.end(), [](double x) { return x == 0.0; }); };
    return zero(s.displacement) && zero(s.velocity);
}

double cpu_seconds() {
    rusage u{};
    getrusage(RUSAGE_SELF, &u);
    return u.ru_utime.tv_sec + u.ru_stime.tv_sec + 1e-6 * (u.ru_utime.tv_usec + u.ru_stime.tv_usec);
}

// Prescribed interface load of a structure run alone: the total force spread evenly over the vertices,
// evaluated at the window midpoint (second-order accurate for smooth profiles).
F64Array prescribed_force(const Value& load, std::size_t vertices, double t_mid) {
    auto f = load.at("force").as_doubles();
    const std::string& profile = load.at("profile").as_string();
    double s = 1.0;
    if (profile == "ramp") s = std::min(1.0, t_mid / load.at("ramp_time").as_double());
    if (profile == "sine") s = std::sin(2 * M_PI * load.at("frequency").as_double() * t_mid);
    F64Array a = F64Array::zeros(vertices, 2);
    for (std::size_t i = 0; i < vertices; ++i) {
        a(i, 0) = s * f[0] / static_cast<double>(vertices);
        a(i, 1) = s * f[1] / static_cast<double>(vertices);
    }
    return a;
}

class Runner {
public:
    explicit Runner(const RunOptions& o) : opt_(o) {}
    int execute();

private:
    void log(const std::string& s) { log(s, s); }
    // `screen` to stderr, `file` to run.log (which others may read: no secrets there).
    void log(const std::string& screen, const std::string& file) {
        progress_finish();
        std::cerr << "sphfsi: " << screen << std::endl;
        if (log_file_) log_file_ << file << std::endl;
    }
    void progress_finish() {
        if (progress_) progress_->finish();
    }
    std::vector<std::string> program_for(const std::string& role) const;
    bool fluid_does_external_work() const;
    void initialise(std::optional<Checkpoint>& resume);
    void loop();
    WindowOutcome advance_alone(const WindowPlan& plan);
    WindowPlan plan_window(double t_stop) const;
    struct Stop {
        double t;         // the time the next windows land on
        bool checkpoint;  // a checkpoint is taken there
    };
    Stop next_stop() const;
    double structure_alone_step() const;
    // Shorter than this, two times are one to the coordinator (a window landing within it of a stop lands on
    // the stop): 1e-12 s, or 1e-12 of end_time where that is longer.
    double time_resolution() const { return 1e-12 * std::max(1.0, end_); }
    double step_wanted(const std::string& role, double dt_wanted, const char* message) const;
    // A resume's copies replace record.h5 and watchpoints.csv, each once the run has reached the time that file
    // ends at: until then it holds more than its copy, and a resume that stops must leave it.
    // Each is tried even when the other fails (the first failure is rethrown): a record that could not be
    // renamed must not also cost the watchpoints' copy, which the clean-up would remove as stopped short.
    void take_over_when_caught_up(double t) {
        std::exception_ptr failed;
        try {
            recorder_->take_over_when_caught_up(t);
        } catch (...) {
            failed = std::current_exception();
        }
        if (watchpoints_) try {
                watchpoints_->take_over_when_caught_up(t);
            } catch (...) {
                if (!failed) failed = std::current_exception();
            }
        if (failed) std::rethrow_exception(failed);
    }
    void record_window(const WindowPlan& plan, const WindowOutcome& o, double wall_s, const InterfaceWork& work);
    void snapshot_all();
    void checkpoint();

    RunOptions opt_;
    std::unique_ptr<DirLock> lock_;  // declared first, released last: after the record's final flush
    Scene scene_;
    std::ofstream log_file_;
    std::unique_ptr<Launcher> launcher_;
    std::unique_ptr<Hub> hub_;
    std::unique_ptr<Session> session_;
    std::unique_ptr<Recorder> recorder_;
    std::unique_ptr<Watchpoints> watchpoints_;
    std::unique_ptr<CouplingScheme> scheme_;
    std::unique_ptr<Schedule> schedule_;
    std::unique_ptr<ProgressDisplay> progress_;
    std::vector<std::string> roles_;
    bool fluid_ = false, structure_ = false, coupled_ = false;
    InterfaceState iface_;
    double t_ = 0.0, t0_ = 0.0, end_ = 0.0, output_dt_ = 0.0, checkpoint_dt_ = 0.0;
    double fluid_dt_ = 0.0, structure_dt_ = 0.0;
    std::uint64_t output_index_ = 0, checkpoint_index_ = 0, windows_ = 0, steps_ = 0;
    double messaging_total_s_ = 0.0, wall_in_loop_s_ = 0.0;
    // The time loop as a whole (windows, recording, snapshots, checkpoints), for the coordinator's CPU share
    // measured over the same interval as its wall time; start-up and shut-down are not in it.
    std::optional<Clock::time_point> loop_start_;
    double loop_cpu_start_ = 0.0;
    // The loop's wall and CPU time in the segments before the checkpoint this run resumed from.
    double loop_wall_before_ = 0.0, loop_cpu_before_ = 0.0;
    double loop_wall_so_far() const {
        return loop_wall_before_ + (loop_start_ ? std::chrono::duration<double>(Clock::now() - *loop_start_).count() : 0.0);
    }
    double loop_cpu_so_far() const { return loop_cpu_before_ + (loop_start_ ? cpu_seconds() - loop_cpu_start_ : 0.0); }
    EnergyLimits energy_limits_;
};

std::vector<std::string> Runner::program_for(const std::string& role) const {
    std::vector<std::string> argv;
    if (auto custom = scene_.custom_program(role)) argv = *custom;
    else argv = {own_directory() + "/sphfsi-" + role};
    argv.insert(argv.end(), {"--connect", hub_->endpoint(), "--name", role});
    return argv;
}

int Runner::execute() {
    std::optional<Checkpoint> resume;
    if (opt_.resume) {
        // A completed run has nothing left: resuming it re-ran its tail from the last checkpoint. Asked first:
        // a run that completed before its first checkpoint has none, and "no checkpoint" misled.
        if (record_status(opt_.out_dir / "record.h5") == "completed") {
            std::cerr << "sphfsi: the run in " << opt_.out_dir.string()
                      << " completed; there is nothing to resume (start a new run to change it)" << std::endl;
            return 2;
        }
        // A record without a checkpoint beside it stopped before its first one (checkpoints come every
        // run.checkpoint_interval, by default 10 output intervals): "no checkpoint at ... (was the run started
        // with a checkpoint interval?)" suggested a setting was missing (a kill probe, 2026-11-28).
        if (!std::filesystem::exists(opt_.out_dir / "checkpoint.bin") && std::filesystem::exists(opt_.out_dir / "record.h5")) {
            const std::string status = record_status(opt_.out_dir / "record.h5");
            std::cerr << "sphfsi: the run in " << opt_.out_dir.string() << " stopped before its first checkpoint"
                      << (status.empty() ? std::string() : " (its record says: " + status + ")")
                      << "; there is nothing to resume from: start it again (--overwrite), with a shorter "
                         "run.checkpoint_interval to resume earlier"
                      << std::endl;
            return 2;
        }
        resume = read_checkpoint(opt_.out_dir / "checkpoint.bin");
        // The scene as the run saw it, not as the file may read now; paths stay relative to the original.
        scene_ = parse_scene(resume->scene_text, resume->scene_file, resume->overrides);
        t_ = resume->t;  // an interruption before INIT completes is reported at the checkpoint's time
    } else {
        scene_ = load_scene(opt_.scene, opt_.overrides, opt_.listen.empty());
        scene_.file = std::filesystem::absolute(opt_.scene);
    }
    std::filesystem::create_directories(opt_.out_dir);  // only once the scene is known to be valid
    lock_ = std::make_unique<DirLock>(opt_.out_dir);
    // An earlier run's record is only replaced on request: a re-run into the same folder that fails at once
    // (a typo in --set, a participant that cannot start) would otherwise have cost the earlier results.
    // record.h5.interrupted too: an older build's resume that died left the history there (Recorder).
    if (!resume && !opt_.overwrite &&
        (std::filesystem::exists(opt_.out_dir / "record.h5") || std::filesystem::exists(opt_.out_dir / "record.h5.interrupted"))) {
        std::cerr << "sphfsi: " << opt_.out_dir.string() << " already holds a run's record (record.h5, or an older "
                  << "build's record.h5.interrupted); pass "
                  << "--overwrite to replace it, --resume " << opt_.out_dir.string()
                  << " to continue it, or choose another --out" << std::endl;
        return 2;
    }
    if (!resume)  // a fresh run: what an earlier run left here must not be resumed or read as this run's
        // (checkpoint.bin.tmp and record.xdmf.tmp are not here: each write replaces its own, and nothing reads them.
        // record.h5.interrupted is: --resume refuses to guess while it is there.)
        for (const char* stale : {"checkpoint.bin", "record.xdmf", "watchpoints.csv", "watchpoints.csv.tmp", "watchpoints.csv.resuming",
                                  "record.h5.resuming", "record.h5.creating", "record.h5.interrupted"})
            std::filesystem::remove(opt_.out_dir / stale);
    log_file_.open(opt_.out_dir / "run.log", resume ? std::ios::app : std::ios::trunc);
    const Value& run = scene_.section("run");
    fluid_ = scene_.has("fluid");
    structure_ = scene_.has("structure");
    coupled_ = fluid_ && structure_;
    if (structure_) roles_.push_back("structure");  // INIT order: the structure publishes the interface first
    if (fluid_) roles_.push_back("fluid");
    end_ = run.at("end_time").as_double();
    output_dt_ = run.number_or("output_interval", end_ / 100);
    checkpoint_dt_ = run.number_or("checkpoint_interval", 10 * output_dt_);
    for (const std::string& w : scene_warnings(scene_)) log("warning: " + w);

    std::signal(SIGINT, on_signal);
    std::signal(SIGTERM, on_signal);
    std::signal(SIGPIPE, SIG_IGN);

    RunMetadata meta{scene_.file.string(), scene_.text, "", kSoftwareVersion, kGitRevision, kProtocolVersion};
    // One per line: a --set value may hold spaces ("load.force=[0.0, -200.0]"), which a space-joined list lost.
    for (const auto& o : scene_.overrides) meta.overrides += (meta.overrides.empty() ? "" : "\n") + o;
    try {
        recorder_ = std::make_unique<Recorder>(opt_.out_dir / "record.h5", meta,
                                               resume ? std::optional<double>(resume->t) : std::nullopt);
    } catch (const std::exception& e) {
        if (log_file_) log_file_ << "error: " << e.what() << std::endl;  // run_scene puts it on stderr
        throw;
    }
    if (resume) {  // the totals cover every window of the record, those before the interruption too
        wall_in_loop_s_ = recorder_->window_column_sum("wall_s");
        messaging_total_s_ = recorder_->window_column_sum("messaging_s");
    }
    std::string status = "completed";
    int code = 0;
    try {
        initialise(resume);
        take_over_when_caught_up(t_);
        loop();
    } catch (const ParticipantFailure& e) {
        log(std::string("error: ") + e.what());
        status = std::string("failed: ") + e.what();
        code = 1;
    } catch (const Interrupted&) {
        log("interrupted at t = " + std::to_string(t_) + " s; the record holds everything up to here");
        status = "interrupted at t = " + std::to_string(t_) + " s";
        code = 130;
    } catch (const std::exception& e) {
        log(std::string("error: ") + e.what());
        status = std::string("failed: ") + e.what();
        code = 1;
    }
    const double loop_cpu = loop_cpu_so_far(), loop_wall = loop_wall_so_far();
    progress_finish();
    // Why the run stopped goes on file before the shutdown, which takes seconds (goodbye, then waiting for
    // the participants to exit): a kill in those seconds left "running" on file with the cause known (a
    // review, 2026-11-28). Written again, final, below; a failure to write it here is reported there.
    if (code != 0) try {
            recorder_->set_status(status);
        } catch (const std::exception&) {
        }
    if (hub_) hub_->goodbye(code == 0 ? 5.0 : 1.0);
    if (launcher_)
        for (const auto& note : launcher_->stop_all(code == 0 ? 2.0 : 0.5)) log("shutdown: " + note);
    // From here on a write that fails (a full disk) is the run's failure, and the status and the clean-up
    // below still follow: escaping, it skipped both, leaving "running" on file and a resume's copies behind
    // (a review, 2026-11-28).
    const auto failed_here = [&](const std::exception& e) {
        if (status.find(e.what()) == std::string::npos) log(std::string("error: ") + e.what());  // once
        if (code == 0) {  // else the run had already stopped, and that stays its cause
            status = std::string("failed: ") + e.what();
            code = 1;
        }
    };
    try {
        double cpu = cpu_seconds();
        recorder_->set_number("coordinator_cpu_s", cpu);
        recorder_->set_number("wall_s", wall_in_loop_s_);
        recorder_->set_number("messaging_and_waiting_s", messaging_total_s_);
        recorder_->set_number("loop_wall_s", loop_wall);
        recorder_->set_number("coordinator_loop_cpu_s", loop_cpu);
        if (coupled_) {
            recorder_->set_number("interface_work", iface_.work_total);
            recorder_->set_number("interface_energy_created", iface_.created_total);
        }
        if (watchpoints_) watchpoints_->flush();
    } catch (const std::exception& e) {
        failed_here(e);
    }
    if (code == 0) {
        // A completed resume replaces the interrupted files whatever time they reached, before its status is
        // set: the status and the sidecar written with it are then the final record's. The sidecar was written
        // only here, after the status, and a failure to write it escaped as an exception with "completed" on
        // file (a review, 2026-11-27). A resume that cannot take over has not completed.
        try {
            take_over_when_caught_up(std::numeric_limits<double>::infinity());
        } catch (const std::exception& e) {
            log(std::string("error: ") + e.what());
            status = std::string("failed: ") + e.what();
            code = 1;
        }
    }
    try {
        if (const std::string written = recorder_->set_status(status); written != status) {  // after every row and total above
            log("error: " + written.substr(std::string("failed: ").size()));
            status = written;
            code = 1;
        }
    } catch (const std::exception& e) {
        failed_here(e);
    }
    if (code != 0) {
        // A resume that reached the interrupted record's end holds all of it and then this stop: its copy
        // replaces the files, as it would have at the end of the window it stopped in (the loop takes over
        // after the window's frames, which can fail). The status already says why the run stopped; a take-over
        // that fails as well is logged, and the rest of the clean-up still runs.
        try {
            take_over_when_caught_up(t_);
        } catch (const std::exception& e) {
            log(std::string("error: ") + e.what());
        }
        // A copy that caught up and could not be renamed holds the whole run: it is kept, and said so.
        const auto kept = [&](const std::string& name) {
            log("the resumed run's copy could not replace " + name + ", which is left as the interrupted run left it; " +
                "the copy, with everything to t = " + std::to_string(t_) + " s, is kept as " + name +
                ".resuming (rename it over " + name + " to use it)");
        };
        if (recorder_->resume_pending()) {
            if (recorder_->resume_rename_failed()) kept(recorder_->file().filename().string());
            else
                log("the resumed run stopped at t = " + std::to_string(t_) + " s, before t = " +
                    std::to_string(recorder_->history_end()) + " s, where the interrupted run's record ends: " +
                    recorder_->file().filename().string() + " is left as that run left it");
            recorder_->abandon_resume();
        }
        if (watchpoints_ && watchpoints_->resume_pending()) {
            if (watchpoints_->resume_rename_failed()) kept("watchpoints.csv");
            else
                log("the resumed run stopped before t = " + std::to_string(watchpoints_->history_end()) +
                    " s, where the interrupted run's watchpoints.csv ends: it is left as that run left it");
            watchpoints_->abandon_resume();
        }
    }
    if (code == 0) log("done: t = " + std::to_string(t_) + " s, " + std::to_string(windows_) + " windows; record in " +
                       recorder_->file().string());
    return code;
}

void Runner::initialise(std::optional<Checkpoint>& resume) {
    const Value& run = scene_.section("run");
    // Progress is seen only with each heartbeat: a stall shorter than two heartbeats could not be told apart.
    const double heartbeat_s = run.at("heartbeat_s").as_double();
    HubTiming timing{heartbeat_s, run.at("timeout_s").as_double(), run.at("startup_timeout_s").as_double(),
                     std::max(run.at("stall_timeout_s").as_double(), 2 * heartbeat_s)};
    if (opt_.listen.empty()) launcher_ = std::make_unique<Launcher>();
    hub_ = std::make_unique<Hub>(opt_.listen.empty() ? "tcp://127.0.0.1:*" : opt_.listen, random_token(), timing,
                                 launcher_.get(), [this](const std::string& s) { log(s); });
    session_ = std::make_unique<Session>(*hub_);
    log("listening on " + hub_->endpoint());
    if (launcher_) {
        for (const auto& role : roles_) launcher_->start(role, program_for(role), hub_->token());
    } else {
        // The token is what keeps another local process out of the run; run.log is readable by others.
        const std::string waiting = "waiting for " + std::to_string(roles_.size()) + " participant(s) at " + hub_->endpoint() +
                                    "; start each with --connect " + hub_->endpoint() + " --name ROLE and SPHFSI_TOKEN=";
        log(waiting + hub_->token(), waiting + "(the token: on stderr only)");
    }
    hub_->await_hellos(roles_);

    t0_ = resume ? resume->t : 0.0;
    t_ = t0_;
    for (const auto& role : roles_) {
        InitRequest req;
        req.config = scene_.section(role);
        req.t0 = t0_;
        if (role == "fluid" && coupled_) {
            req.interface = iface_.mesh;
            if (!resume && !at_rest_undeformed(iface_)) {
                // The structure starts deformed or moving: the fluid must place its solid particles there.
                if (hub_->peers().at("fluid").version < 2)
                    throw ParticipantFailure("fluid", "bad_config",
                                             "speaks protocol 1, which cannot start from the structure's deformed or "
                                             "moving interface at t0 (protocol 2 passes it in INIT interface_state)");
                req.interface_state = {{"displacement", iface_.displacement}, {"velocity", iface_.velocity}};
            }
        }
        if (resume) req.state = resume->states.at(role);
        Message m = hub_->request(role, MessageType::Init, req);
        const auto& ready = m.as<InitReply>();
        const double dt_wanted = step_wanted(role, ready.dt_wanted, "READY");  // the first window is sized by it
        if (role == "structure") {
            // A structure alone may have no wetted surface; coupled, the fluid needs one to push on.
            if (!ready.interface && coupled_)
                throw ParticipantFailure(role, "bad_config", "publishes no interface mesh (no wetted member) in a coupled scene");
            InterfaceMesh mesh = ready.interface ? *ready.interface : InterfaceMesh{F64Array({0, 2}, {}), I32Array({0, 4}, {})};
            // The scene's [load] is spread over the interface's vertices: with none it acted on nothing, and the
            // run completed as if it had (a foreign structure that published no mesh; a review, 2026-11-28).
            if (mesh.vertices.rows() == 0 && scene_.tree.find("load"))
                throw ParticipantFailure(role, "bad_config", "publishes no interface vertices, and the scene's [load] is "
                                                             "spread over them: it would act on nothing");
            iface_.reset(mesh);
            recorder_->set_interface(mesh);
            if (!ready.interface_state.empty()) {  // protocol 2: a deformed or moving start (else at rest, undeformed)
                const auto n = iface_.vertices();
                iface_.displacement = vertex_field(role, ready.interface_state, "displacement", n);
                iface_.velocity = vertex_field(role, ready.interface_state, "velocity", n);
                // Where the fluid will be told the interface is (INIT below), and no motion before t0 to extrapolate.
                iface_.previous_displacement = iface_.fluid_displacement = iface_.displacement;
            }
            structure_dt_ = dt_wanted;
        } else {
            fluid_dt_ = dt_wanted;
        }
        try {
            recorder_->set_participant(role, hub_->peers().at(role).software, ready.info);
        } catch (const RecordRefused& e) {
            throw ParticipantFailure(role, "garbage", e.what());
        }
    }
    if (structure_)
        watchpoints_ = std::make_unique<Watchpoints>(opt_.out_dir / "watchpoints.csv", scene_.tree, iface_.mesh,
                                                     resume.has_value(), t0_);
    if (coupled_) {
        const Value& c = scene_.section("coupling");
        schedule_ = std::make_unique<Schedule>(c);
        scheme_ = make_scheme(c, *session_, [this](const std::string& s) { log(s); });
        energy_limits_.max_created = c.at("max_created_energy").as_double();
        energy_limits_.max_gain = c.at("max_energy_gain").as_double();
        energy_limits_.external_work = fluid_does_external_work();
    }
    if (resume) {
        InterfaceState saved = resume->interface;
        iface_ = saved;
        output_index_ = resume->output_index;
        checkpoint_index_ = resume->checkpoint_index;
        windows_ = resume->windows;
        steps_ = resume->steps;
        fluid_dt_ = resume->fluid_dt;
        structure_dt_ = resume->structure_dt;
        loop_wall_before_ = resume->loop_wall_s;
        loop_cpu_before_ = resume->loop_cpu_s;
        log("resumed at t = " + std::to_string(t0_) + " s");
    } else {
        snapshot_all();  // frame 0: the initial state
        if (watchpoints_) watchpoints_->write(t_, iface_.displacement);
    }
    recorder_->set_text("window_rule_legend", window_rule_legend());
    progress_ = std::make_unique<ProgressDisplay>(t0_, end_, opt_.quiet, steps_);
}

// Wind on the free surface or a sliding lid does work on the fluid, so the pair's energy may rise: the energy
// guard's total check is off for such scenes. So does gravity along a periodic axis, the way a channel is
// driven by a mean pressure gradient (docs/scenes.md, fluid.gravity): water crossing the seam keeps its speed
// and re-enters a period higher, and the potential energy the fluid reports jumps by m g L each time (a
// review's gravity-driven channel stopped as "coupling diverged" with nothing diverging).
bool Runner::fluid_does_external_work() const {
    auto nonzero = [&](std::string_view path, int component = -1) {
        const Value* v = find_path(scene_.tree, path);
        if (!v || !v->is_array()) return false;
        const auto& a = v->as_array();
        for (std::size_t i = 0; i < a.size(); ++i)
            if ((component < 0 || static_cast<int>(i) == component) && a[i].is_number() && a[i].as_double() != 0.0)
                return true;
        return false;
    };
    const Value* section = scene_.tree.find("fluid");
    const sphfsi::fluid::PeriodicAxes axes = section ? sphfsi::fluid::periodic_axes(*section) : sphfsi::fluid::PeriodicAxes{};
    const bool driven_along_period = (axes.x && nonzero("fluid.gravity", 0)) || (axes.y && nonzero("fluid.gravity", 1));
    return nonzero("fluid.free_surface.wind_shear") || nonzero("fluid.tank.lid_velocity") || driven_along_period;
}

WindowPlan Runner::plan_window(double t_stop) const {
    if (coupled_) return schedule_->next(t_, fluid_dt_, structure_dt_, t_stop);
    WindowPlan p;
    p.t = t_;
    if (fluid_) {  // alone, the fluid runs adaptively all the way to the next output
        p.rule = WindowRule::FluidAlone;
        p.dt = p.wanted = t_stop - t_;
        p.fluid_substeps = 0;
        return p;
    }
    p.rule = WindowRule::StructureAlone;
    // A load that changes in time is sampled once per window, so the structure then takes one step per
    // window; otherwise it runs adaptively to the next output in one request (no messaging per step).
    const Value* load = scene_.tree.find("load");
    if (!load || load->at("profile").as_string() == "constant") {
        p.dt = p.wanted = t_stop - t_;
        p.structure_substeps = 0;
        return p;
    }
    p.dt = p.wanted = structure_alone_step();
    p.structure_substeps = 1;
    land_on_stop(p, t_stop);
    return p;
}

// A structure run alone under a load that changes in time steps once per window, at its own step or, for a
// sine, at most 1/20 of a period: sampled once per structure step, a frequency above half the step rate
// folded back onto a lower one (a review ran 1/dt - 100 Hz, and it moved the beam as 100 Hz did, to
// round-off). Held over 1/20 of a period, midpoint samples carry the sine's own frequency at
// sin(pi/20)/(pi/20) = 0.996 of its amplitude.
double Runner::structure_alone_step() const {
    const Value* load = scene_.tree.find("load");
    if (load && load->at("profile").as_string() == "sine")
        return std::min(structure_dt_, 1.0 / (20.0 * load->at("frequency").as_double()));
    return structure_dt_;
}

// A participant's step sizes the windows (coupled, or a structure alone under a load that changes in time),
// so one shorter than the coordinator's time resolution would never reach the end: a structure alone that
// wanted 1e-19 s took 1e-19 s windows at 7000 a second, for ever (a review, 2026-11-28). A real solver's
// step collapses like that only when it diverged; it stops the run, naming the participant.
double Runner::step_wanted(const std::string& role, double dt_wanted, const char* message) const {
    if (!(dt_wanted > 0) || !std::isfinite(dt_wanted))
        throw ParticipantFailure(role, "garbage", std::string(message) + " wants a step of " + seconds(dt_wanted));
    if (dt_wanted < time_resolution())
        throw ParticipantFailure(role, "diverged", std::string(message) + " wants a step of " + seconds(dt_wanted) +
                                                       ", below the coordinator's time resolution of " +
                                                       seconds(time_resolution()) +
                                                       " (1e-12 s, or 1e-12 of run.end_time): its step has collapsed");
    return dt_wanted;
}

// Windows land exactly on frame times (frame k at k * output_interval; frame 0 is the initial state), on
// checkpoint times (checkpoint k at k * checkpoint_interval) and on the end, never past it. Two of these closer
// than a sliver are taken as one, or the gap between them would be a window of its own, down to 1e-11 s
// (whose fluid force had been 25 times its neighbours'): a frame due a sliver before the end is taken at the end,
// and a checkpoint due within a sliver of a frame, or of the end, is taken with that frame, or not at all (a
// resume needs none at the end). Frames keep their times. A sliver is a quarter of the window the coupling
// rule wants, or of the participant's own step when it runs alone (its window is then the whole gap, except a
// structure's under a load that changes in time: structure_alone_step), or of the output or checkpoint
// interval where that is shorter: windows are no longer than those anyway, and a larger
// sliver would fold several frames due before the end into the end's one.
Runner::Stop Runner::next_stop() const {
    const double frame_due = std::min(output_index_ * output_dt_, end_);
    const double checkpoint_due = (checkpoint_index_ + 1) * checkpoint_dt_;
    // The sliver of a structure alone is of the window it takes, which a sine shortens (the structure's own
    // step folded a frame due 0.4 ms before the end into the end's, and many shorter windows then crossed
    // its time: it was recorded at 0.10001 s, not 0.1 s; a review, 2026-11-27).
    const double window = coupled_ ? plan_window(std::min(frame_due, checkpoint_due)).wanted
                                   : (fluid_ ? fluid_dt_ : structure_alone_step());
    const double sliver = 0.25 * std::min({window, output_dt_, checkpoint_dt_});
    const double frame = end_ - frame_due < sliver ? end_ : frame_due;
    if (checkpoint_due >= end_ - sliver) return {frame, false};
    if (std::abs(checkpoint_due - frame) < sliver) return {frame, true};
    return checkpoint_due < frame ? Stop{checkpoint_due, true} : Stop{frame, false};
}

WindowOutcome Runner::advance_alone(const WindowPlan& p) {
    WindowOutcome o;
    if (fluid_) {
        o.fluid = session_->advance("fluid", p.t, p.dt, p.fluid_substeps, 0, {});
        return o;
    }
    Fields inputs;
    if (const Value* load = scene_.tree.find("load")) iface_.force = prescribed_force(*load, iface_.vertices(), p.t + 0.5 * p.dt);
    inputs["force"] = iface_.force;
    o.structure = session_->advance("structure", p.t, p.dt, p.structure_substeps, 0, std::move(inputs));
    iface_.previous_displacement = iface_.displacement;
    iface_.previous_dt = p.dt;
    iface_.displacement = vertex_field("structure", o.structure.reply.outputs, "displacement", iface_.vertices());
    iface_.velocity = vertex_field("structure", o.structure.reply.outputs, "velocity", iface_.vertices());
    return o;
}

void Runner::loop() {
    loop_start_ = Clock::now();
    loop_cpu_start_ = cpu_seconds();
    const double eps = time_resolution();
    while (t_ < end_ - eps) {
        const Stop stop = next_stop();
        const double t_stop = stop.t;
        const WindowPlan plan = plan_window(t_stop);
        const F64Array structure_start = iface_.displacement, fluid_start = iface_.fluid_displacement;
        auto start = Clock::now();
        WindowOutcome o = coupled_ ? scheme_->run(plan, iface_) : advance_alone(plan);
        double wall = std::chrono::duration<double>(Clock::now() - start).count();
        t_ = (plan.t + plan.dt >= t_stop - eps) ? t_stop : plan.t + plan.dt;
        if (fluid_) fluid_dt_ = o.fluid.reply.dt_wanted;
        if (structure_) structure_dt_ = o.structure.reply.dt_wanted;
        ++windows_;
        steps_ += fluid_ ? o.fluid.reply.substeps : o.structure.reply.substeps;
        InterfaceWork work;
        if (coupled_)
            work = interface_work(o.structure_force, iface_.force, structure_start, iface_.displacement, fluid_start,
                                  iface_.fluid_displacement);
        record_window(plan, o, wall, work);
        if (watchpoints_) watchpoints_->write(t_, iface_.displacement);
        // After the window is recorded, so that a run stopped here keeps the window that stopped it (and the
        // root's interface totals, taken from the energy account, include it).
        if (coupled_)
            if (const std::string off = account_energy(energy_limits_, windows_, t_, o, work, iface_); !off.empty())
                log("warning: " + off);
        if (!o.stop_run.empty()) throw std::runtime_error(o.stop_run);
        // The window is whole and recorded; a step that collapsed is the next one's failure.
        if (fluid_) step_wanted("fluid", fluid_dt_, "ADVANCED");
        if (structure_) step_wanted("structure", structure_dt_, "ADVANCED");
        progress_->update(t_, steps_);
        // Frames at k * output_interval, and the end's state whether or not end_time is one of those.
        if (t_ >= output_index_ * output_dt_ - eps || t_ >= end_ - eps) snapshot_all();
        // A resume's copy takes over before a checkpoint of this time is published. The other way round, a
        // kill between the two left a checkpoint at t beside the interrupted record, whose last flush may have
        // been cut inside this window's rows: the next resume kept its rows before t, started after t, and
        // the window was gone from the record for good (a review of the recorder, 2026-11-27).
        take_over_when_caught_up(t_);
        if (stop.checkpoint && t_ == t_stop) checkpoint();
    }
}

void Runner::record_window(const WindowPlan& p, const WindowOutcome& o, double wall_s, const InterfaceWork& work) {
    // Messaging and waiting: the part of each round trip not spent computing in the participant. When both
    // sides advanced at once their round trips overlap, and the window waited for the longer one only: its
    // overhead alone counts (summing both came out above the window's wall time).
    double fluid_overhead = fluid_ ? std::max(0.0, o.fluid.roundtrip_s - o.fluid.reply.compute_s) : 0.0;
    double structure_overhead = structure_ ? std::max(0.0, o.structure.roundtrip_s - o.structure.reply.compute_s) : 0.0;
    if (o.concurrent) {
        const bool fluid_last = o.fluid.roundtrip_s >= o.structure.roundtrip_s;
        (fluid_last ? structure_overhead : fluid_overhead) = 0.0;
    }
    messaging_total_s_ += fluid_overhead + structure_overhead;
    wall_in_loop_s_ += wall_s;
    std::vector<std::pair<std::string, double>> row{
        {"t", t_},
        {"dt", p.dt},
        {"rule", static_cast<double>(p.rule)},
        {"clipped", p.clipped ? 1.0 : 0.0},
        {"fluid_substeps", static_cast<double>(o.fluid.reply.substeps)},
        {"structure_substeps", static_cast<double>(o.structure.reply.substeps)},
        {"iterations", static_cast<double>(o.iterations)},
        {"residual", o.residual},
        {"converged", o.converged ? 1.0 : 0.0},
        {"fluid_dt_wanted", fluid_dt_},
        {"structure_dt_wanted", structure_dt_},
        {"fluid_solver_iterations", static_cast<double>(o.fluid.reply.solver_iterations)},
        {"structure_solver_iterations", static_cast<double>(o.structure.reply.solver_iterations)},
        {"fluid_compute_s", o.fluid.reply.compute_s},
        {"structure_compute_s", o.structure.reply.compute_s},
        {"fluid_roundtrip_s", o.fluid.roundtrip_s},
        {"structure_roundtrip_s", o.structure.roundtrip_s},
        {"messaging_s", fluid_overhead + structure_overhead},
        {"wall_s", wall_s},
    };
    if (coupled_) {
        row.emplace_back("interface_work", work.on_structure);
        row.emplace_back("interface_energy_created", work.created);
    }
    // Numbers a participant reports in ADVANCED.stats (e.g. the fluid's largest density error) become
    // columns "ROLE.NAME"; the set is fixed by the first window, later windows fill missing ones with NaN.
    auto add_stats = [&](const std::string& role, const Value& stats) {
        if (!stats.is_table()) return;
        for (const auto& [k, v] : stats.as_table())
            row.emplace_back(role + "." + k, v.as_double());  // Session checked: plain names, numbers
    };
    if (fluid_) add_stats("fluid", o.fluid.reply.stats);
    if (structure_) add_stats("structure", o.structure.reply.stats);
    for (const auto& name : recorder_->append_window(row, structure_ ? &iface_.displacement : nullptr,
                                                     structure_ ? &iface_.force : nullptr))
        log("warning: window column '" + name + "' first appeared after the first window and is not recorded "
            "(the columns are fixed by the first window)");
}

void Runner::snapshot_all() {
    for (const auto& role : roles_) {
        Message m = hub_->request(role, MessageType::Snapshot);
        const Frame& frame = m.as<Frame>();
        if (!same_instant(frame.t, t_, output_dt_))
            throw ParticipantFailure(role, "garbage", "sent a FRAME of t = " + seconds(frame.t) + " at t = " + seconds(t_));
        try {
            recorder_->append_frame(role, t_, frame.fields);
        } catch (const RecordRefused& e) {
            throw ParticipantFailure(role, "garbage", e.what());
        }
    }
    if (watchpoints_) watchpoints_->flush();
    ++output_index_;
}

void Runner::checkpoint() {
    Checkpoint c;
    c.scene_file = scene_.file.string();
    c.scene_text = scene_.text;
    c.overrides = scene_.overrides;
    c.t = t_;
    c.output_index = output_index_;
    c.checkpoint_index = checkpoint_index_ + 1;
    c.windows = windows_;
    c.steps = steps_;
    c.fluid_dt = fluid_dt_;
    c.structure_dt = structure_dt_;
    c.interface = iface_;
    c.loop_wall_s = loop_wall_so_far();
    c.loop_cpu_s = loop_cpu_so_far();
    for (const auto& role : roles_) {
        Message m = hub_->request(role, MessageType::Checkpoint);
        const State& state = m.as<State>();
        if (!same_instant(state.t, t_, checkpoint_dt_))
            throw ParticipantFailure(role, "garbage", "sent a STATE of t = " + seconds(state.t) + " at t = " + seconds(t_));
        // INIT reads empty state bytes as "start fresh": a resume from them would silently restart at t = 0.
        if (state.bytes.empty()) throw ParticipantFailure(role, "garbage", "sent a STATE with no bytes");
        c.states[role] = state.bytes;
    }
    // Everything up to the checkpoint on disk before it exists: a resume keeps only what it finds there.
    recorder_->flush();
    if (watchpoints_) watchpoints_->flush();
    write_checkpoint(opt_.out_dir / "checkpoint.bin", c);
    ++checkpoint_index_;
}
}  // namespace

int run_scene(const RunOptions& options) {
    try {
        return Runner(options).execute();
    } catch (const ConfigError& e) {
        std::cerr << "sphfsi: invalid scene:\n" << e.what() << std::endl;
        return 2;
    } catch (const std::exception& e) {
        std::cerr << "sphfsi: " << e.what() << std::endl;
        return 1;
    }
}

}  // namespace sphfsi::coordinator
