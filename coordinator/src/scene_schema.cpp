// The keys of a whole scene: the coordinator's own sections here, [fluid] and [structure] from the
// solver libraries' schemas (so a scene is checked completely before any process starts).
#include <algorithm>
#include <cctype>

#include "sphfsi/protocol/codec.hpp"
#include "sphfsi/coordinator/scene.hpp"
#include "sphfsi/coordinator/scene_cross_checks.hpp"
#include "sphfsi/fluid/schema.hpp"
#include "sphfsi/structure/schema.hpp"

namespace sphfsi::coordinator {
namespace {

void run_section(schema::TableSchema& s) {
    auto& run = s.table("run", "How long to run, how often to record, and how patient to be with participants.", true);
    run.string("title", "Free text recorded with the run.").fallback("");
    run.number("end_time", "Simulated time at which the run ends.").unit("s").greater_than(0).at_most(1e6).required();
    run.number("output_interval", "Simulated time between recorded frames (default: end_time / 100).")
        .unit("s").greater_than(0).at_most(1e6);
    run.number("checkpoint_interval", "Simulated time between checkpoints for --resume (default: 10 output intervals).")
        .unit("s").greater_than(0).at_most(1e6);
    run.number("timeout_s", "A participant silent this long (no reply, no heartbeat) is declared dead.")
        .unit("s").greater_than(0).at_most(3600).fallback(3.0);
    run.number("heartbeat_s", "Heartbeat period asked of every participant (must be well below timeout_s).")
        .unit("s").greater_than(0).at_most(60).fallback(0.5);
    run.number("startup_timeout_s", "Time a participant has to connect and say HELLO.")
        .unit("s").greater_than(0).at_most(3600).fallback(10.0);
    run.number("stall_timeout_s", "A participant whose heartbeats go on but whose sub-step count (HEARTBEAT progress) "
                                  "stands still this long during an ADVANCE, or which leaves another request (INIT, SNAPSHOT, ...) "
                                  "unanswered this long, is declared hung (at least 2 heartbeat_s is used). One sub-step of the "
                                  "built-in solvers takes well under a second; raise it for a foreign solver with slower steps.")
        .unit("s").greater_than(0).at_most(1e5).fallback(30.0);
    run.check([](const Value& t, const std::string& path, schema::Errors& e) {
        const double heartbeat = t.at("heartbeat_s").as_double(), timeout = t.at("timeout_s").as_double();
        if (heartbeat * 2 > timeout) {
            // Named where the scene wrote it: a heartbeat left at its default is the timeout's doing.
            const bool written = t.at("heartbeat_s").line != 0;
            e.add(written ? &t.at("heartbeat_s") : &t.at("timeout_s"),
                  "key '" + path + (written ? ".heartbeat_s'" : ".timeout_s'") + ": " + path + ".heartbeat_s = " +
                      schema::number_text(heartbeat) + " s" + (written ? "" : " (the default)") + " must be at most half of " + path +
                      ".timeout_s = " + schema::number_text(timeout) + " s, or a healthy participant would look dead; allowed: " +
                      "heartbeat_s <= " + schema::number_text(timeout / 2) + " s, or timeout_s >= " + schema::number_text(2 * heartbeat) + " s");
        }
        // Every frame and checkpoint is a window boundary and a write: a run asking for more than this many
        // is a typo (1e-300 for 1e-3), and would crawl while it filled the disk.
        constexpr double kMaxFrames = 1e6;
        const double end = t.at("end_time").as_double();
        for (const char* key : {"output_interval", "checkpoint_interval"})
            if (const Value* v = t.find(key); v && end / v->as_double() > kMaxFrames)
                e.add(v, "key '" + path + "." + key + "': must be at least " + path + ".end_time / 1e6 = " +
                             schema::number_text(end / kMaxFrames) + " s (at most a million " +
                             (std::string(key) == "output_interval" ? "frames" : "checkpoints") + " per run)");
    });
}

void coupling_section(schema::TableSchema& s) {
    auto& c = s.table("coupling", "How the fluid and the structure advance together (coupled scenes only).");
    c.choice("scheme", {"serial-explicit", "parallel-explicit", "implicit-fixed", "implicit-aitken", "implicit-iqn-ils"},
             "Coupling scheme; see docs/coupling.md.").fallback("serial-explicit");
    c.choice("window", {"thesis", "multi-rate", "fixed"},
             "thesis: one fluid step per window, structure sub-cycled n = int(dt_f/dt_s)+1 times; multi-rate: a "
             "window spans several fluid steps; fixed: window_dt.").fallback("thesis");
    c.number("window_dt", "Window length for window = \"fixed\".").unit("s").greater_than(0).at_most(10);
    // "resolve" by default: the thesis's rule, and what a structure about as heavy as the water it moves needs to
    // keep its own dynamics. A light one needs "window" (measured: docs/validation.md, "Added mass").
    c.choice("structure_steps", {"resolve", "window"},
             "resolve: the structure sub-cycles each window at the step it wants (thesis windows: n = int(dt_f/dt_s)+1); "
             "window: one structure step per window, which a structure much lighter than the fluid it carries needs "
             "under implicit coupling, with structure.time.integrator = \"backward_euler\" (docs/coupling.md).")
        .fallback("resolve");
    c.integer("max_fluid_steps", "multi-rate: the window is this many times the fluid's wanted step at the window's "
                                 "start; the fluid then steps at its own CFL step inside it, so a window can take a "
                                 "few steps more or fewer.")
        .at_least(1).at_most(100000).fallback(10);
    c.choice("predictor", {"none", "linear", "quadratic"},
             "Interface displacement predicted for the window's end: what explicit schemes give the fluid, and implicit "
             "schemes' first iterate (docs/coupling.md).")
        .fallback("linear");
    c.number("tolerance_rel", "Implicit: converged when |residual| <= tolerance_rel |displacement| + tolerance_abs "
                              "sqrt(vertices) (2-norms over all vertices).")
        .greater_than(0).at_most(1).fallback(1e-3);
    c.number("tolerance_abs", "Implicit: absolute part of the convergence test, an RMS length per vertex.").unit("m").at_least(0).at_most(1).fallback(1e-9);
    c.integer("max_iterations", "Implicit: iteration cap per window.").at_least(1).at_most(1000).fallback(30);
    c.choice("on_max_iterations", {"warn", "error"}, "Implicit: what hitting the cap does.").fallback("warn");
    c.number("relaxation", "Implicit: initial (fixed-point: constant) under-relaxation factor.").greater_than(0).at_most(1).fallback(0.5);
    c.integer("iqn_reuse", "IQN-ILS: past windows whose secant pairs are reused.").at_least(0).at_most(100).fallback(8);
    // 1: energy beyond all the fluid had is not physics. Measured (docs/coupling.md): stable couplings created
    // up to 0.29 of it (explicit multi-rate windows on the elastic gate), added-mass blow-ups passed 1 at
    // t = 0.16 s and reached 1.7 and 11 times it by t = 0.4 s.
    c.number("max_created_energy",
             "Stop the run as diverged when the energy the coupling has created at the interface exceeds this "
             "multiple of the fluid's mechanical energy after the first window; off when that energy is not "
             "positive (docs/coupling.md); 0 = never.")
        .at_least(0).fallback(1.0);
    // 0.05: stable coupled runs rose at most 0.2 % of E_f above their first window (elastic gate at 1 and 2 mm,
    // thesis and multi-rate windows; elastic obstacle at 2 mm to 1 s; the added-mass plate at mass ratios
    // 0.03 and 0.1), the explicit added-mass blow-up without a predictor 40 % by t = 0.04 s (docs/coupling.md).
    c.number("max_energy_gain",
             "Stop the run as diverged when the fluid's plus the structure's mechanical energy rises above its "
             "value after the first window by more than this multiple of the fluid's mechanical energy; off when "
             "the scene does work on the fluid (wind, a moving lid, gravity along a periodic axis) or that energy "
             "is not positive (docs/coupling.md); 0 = never.")
        .at_least(0).fallback(0.05);
}

void load_section(schema::TableSchema& s) {
    auto& l = s.table("load", "Prescribed interface force for a structure run alone, spread evenly over the interface vertices. "
                              "Each share acts where its vertex is, as a fluid's force would: on a member whose "
                              "interface_padding differs between its sides, a force along the member also turns it "
                              "(the two faces' moment arms no longer cancel).");
    l.vector("force", 2, "Total force (x, y) on the interface.").unit("N/m").fallback(Value::Array{0.0, 0.0});
    l.choice("profile", {"constant", "ramp", "sine"}, "constant from t = 0; ramp: linear over ramp_time then constant; "
             "sine: force * sin(2 pi frequency t).").fallback("constant");
    l.number("ramp_time", "Duration of the ramp.").unit("s").greater_than(0).fallback(1.0);
    l.number("frequency", "Frequency of the sine profile. The load is held at its midpoint value over each window, "
                          "and windows are at most 1/20 of its period (shorter than the structure's own step if need be).")
        .unit("Hz").greater_than(0).at_most(1e6).fallback(1.0);  // windows of 1/(20 f): 50 ns at 1 MHz
}

// A name is a column label for charts and tools, not a description: 64 characters is room enough, and it keeps
// every watchpoints.csv row short.
constexpr std::size_t kMaxWatchpointName = 64;

void watchpoint_section(schema::TableSchema& s) {
    auto& w = s.table_array("watchpoint", "A named point on the structure whose displacement goes to watchpoints.csv.");
    w.string("name", "Name in watchpoints.csv, e.g. tip: letters, digits, '_', '.' and '-', at most " +
                         std::to_string(kMaxWatchpointName) + " of them.").required();
    w.number("x", "Reference position x.").unit("m").required();
    w.number("y", "Reference position y.").unit("m").required();
    // watchpoints.csv is written unquoted, and a resume keeps its rows by their comma count: a comma or a
    // line break in a name would cut the earlier rows off.
    w.check([](const Value& t, const std::string& path, schema::Errors& e) {
        const std::string& name = t.at("name").as_string();
        const bool plain = !name.empty() && name.size() <= kMaxWatchpointName &&
                           std::all_of(name.begin(), name.end(), [](char c) {
                               return std::isalnum(static_cast<unsigned char>(c)) || c == '_' || c == '.' || c == '-';
                           });
        if (!plain)
            e.add(&t.at("name"), "key '" + path + ".name': got \"" + protocol::printable(name) +
                                     "\"; allowed: a non-empty name of at most " + std::to_string(kMaxWatchpointName) +
                                     " letters, digits, '_', '.' and '-'");
    });
}

// Two watchpoints of one name would be two curves under one label in watchpoints.csv.
void check_watchpoint_names(const Value& scene, schema::Errors& e) {
    const Value* points = scene.find("watchpoint");
    if (!points) return;
    const auto& list = points->as_array();
    for (std::size_t i = 0; i < list.size(); ++i)
        for (std::size_t j = 0; j < i; ++j)
            if (list[i].at("name").as_string() == list[j].at("name").as_string())
                e.add(&list[i].at("name"), "key 'watchpoint[" + std::to_string(i) + "].name': \"" +
                                               protocol::printable(list[i].at("name").as_string()) + "\" is watchpoint[" + std::to_string(j) +
                                               "]'s name too; allowed: a name of its own");
}

void participants_section(schema::TableSchema& s) {
    auto& p = s.table("participants", "Replace a built-in participant by another program (its section is then "
                                      "checked by that program at INIT). The program, when its path has a slash, and "
                                      "arguments written ./x or ../x are relative to the scene file.");
    p.string("fluid", "Command line of the fluid program.");
    p.string("structure", "Command line of the structure program.");
    p.check([](const Value& t, const std::string& path, schema::Errors& e) {
        for (const auto& [role, cmd] : t.as_table())
            if (cmd.is_string() && cmd.as_string().find_first_not_of(" \t") == std::string::npos)
                e.add(&cmd, "key '" + path + "." + role + "': empty; allowed: a command line, program first");
    });
}

void add_solver_section(schema::TableSchema& s, const std::string& role, const schema::TableSchema& builtin,
                        const std::vector<std::string>& external) {
    if (std::find(external.begin(), external.end(), role) != external.end()) {
        s.free_table(role, "Section of the custom " + role + " program (checked by it).");
        return;
    }
    schema::TableSchema& t = s.table(role, builtin.doc());
    t = builtin;
}

}  // namespace

schema::TableSchema scene_schema(const std::vector<std::string>& external) {
    schema::TableSchema s("A scene: one TOML file. Present sections decide which participants start.");
    run_section(s);
    participants_section(s);
    coupling_section(s);
    load_section(s);
    watchpoint_section(s);
    add_solver_section(s, "fluid", fluid::scene_schema(), external);
    add_solver_section(s, "structure", structure::scene_schema(), external);
    s.check([external](const Value& t, const std::string&, schema::Errors& e) {
        bool fluid = t.contains("fluid"), structure = t.contains("structure");
        if (!fluid && !structure) e.add(&t, "the scene has neither [fluid] nor [structure]; it needs at least one");
        if (t.contains("load") && !structure) e.add(t.find("load"), "[load] drives a structure, but the scene has no [structure]");
        if (t.contains("load") && fluid)
            e.add(t.find("load"), "[load] is for a structure run alone; with a [fluid] the fluid provides the load");
        if (t.contains("coupling") && !(fluid && structure))
            e.add(t.find("coupling"), "[coupling] needs both [fluid] and [structure]");
        if (t.contains("watchpoint") && !structure) e.add(t.find("watchpoint"), "watchpoints sit on the structure, but there is no [structure]");
        if (const Value* p = t.find("participants"))
            for (const auto& [role, cmd] : p->as_table())
                if (!t.contains(role)) e.add(&cmd, "key 'participants." + role + "': the scene has no [" + role + "] section");
        if (const Value* c = t.find("coupling")) {
            const bool fixed = c->at("window").as_string() == "fixed";
            if (fixed && !c->contains("window_dt"))
                e.add(c, "missing key 'coupling.window_dt'; required when coupling.window = \"fixed\"");
            if (!fixed && c->contains("window_dt"))  // silently ignored, it would read as if it set the windows
                e.add(&c->at("window_dt"), "key 'coupling.window_dt': used only with coupling.window = \"fixed\" (this "
                                           "scene's is \"" + c->at("window").as_string() + "\"); remove it or set the window rule");
            // max_fluid_steps is not refused likewise: a multi-rate scene keeps it when a --set switches the rule
            // (scenarios/elastic_gate.toml tells how to run it with the thesis's windows).
        }
        if (const Value* l = t.find("load"))  // a key of another profile, written, would be ignored as silently
            for (const auto& [key, profile] : {std::pair<const char*, const char*>{"ramp_time", "ramp"}, {"frequency", "sine"}})
                if (l->at(key).line != 0 && l->at("profile").as_string() != profile)
                    e.add(&l->at(key), std::string("key 'load.") + key + "': used only with load.profile = \"" + profile +
                                           "\" (this scene's is \"" + l->at("profile").as_string() + "\"); remove it or set the profile");
        check_watchpoint_names(t, e);
        check_across_sections(t, external, e);
    });
    return s;
}

std::string scene_reference() { return scene_schema().document(""); }

}  // namespace sphfsi::coordinator
