// The [structure] schema: defaults, ranges and the cross-key rules the coordinator relies on.
#include <doctest/doctest.h>

#include "scenes.hpp"
#include "sphfsi/structure/schema.hpp"

using namespace structure_test;
using sphfsi::ConfigError;
using sphfsi::structure::scene_schema;
using sphfsi::structure::validated_config;

namespace {
// The message of the ConfigError the scene raises ("" when it is valid).
std::string problem(const Value& scene) {
    try {
        validated_config(scene);
    } catch (const ConfigError& e) {
        return e.what();
    }
    return "";
}
bool mentions(const std::string& s, const std::string& what) { return s.find(what) != std::string::npos; }
}  // namespace

TEST_SUITE("schema") {
TEST_CASE("an empty preload is no static start beside a mode start") {
    // preload = [] loads nothing, and the solver starts from the mode alone; the schema refused the pair as two
    // starts (a review, 2026-11-27). A preload that loads is still refused beside a mode.
    Value s = beam(10);
    sphfsi::set_path(s, "initial", table({{"mode", Value(1)}, {"mode_amplitude", Value(0.01)}, {"preload", Value(Value::Array{})}}));
    CHECK(problem(s) == "");
    sphfsi::set_path(s, "initial.preload", Value(Value::Array{point_load(L, 0, 0, -1)}));
    CHECK(mentions(problem(s), "exclude each other"));
}

TEST_CASE("a minimal scene validates and gets every default, also of absent sub-tables") {
    const Value v = validated_config(beam(10));
    CHECK(v.at("mass").as_string() == "consistent");
    CHECK(v.at("section").at("depth").as_double() == 1.0);
    CHECK(v.at("time").at("integrator").as_string() == "generalized_alpha");
    CHECK(v.at("time").at("rho_inf").as_double() == 0.9);
    CHECK(v.at("newton").at("max_iterations").as_int() == 25);
    CHECK(v.at("damping").at("model").as_string() == "none");
    CHECK(v.at("initial").at("mode").as_int() == 0);
    CHECK(v.at("members").as_array()[0].at("wetted").as_bool());
}

TEST_CASE("types, ranges and unknown keys are reported with their dotted path") {
    Value s = beam(10);
    set(s, "material.E", Value(-1.0));
    CHECK(mentions(problem(s), "structure.material.E"));
    s = beam(10);
    set(s, "time.rho_inf", Value(1.5));
    CHECK(mentions(problem(s), "structure.time.rho_inf"));
    s = beam(10);
    set(s, "time.integrator", Value("rk4"));
    CHECK(mentions(problem(s), "\"generalized_alpha\""));
    s = beam(10);
    set(s, "sectoin", Value(Value::Table{}));
    CHECK(mentions(problem(s), "unknown key 'structure.sectoin'"));
    s = beam(10);
    s.as_table_mut().erase("material");
    CHECK(mentions(problem(s), "missing required key 'structure.material'"));
    // A coordinator-sized typo: 1e300 used to pass and then fail the modal analysis naming no key.
    s = beam(10);
    set(s, "members[0].end", vec(1.0, 1e300));
    CHECK(mentions(problem(s), "key 'structure.members[0].end': an entry is 1e+300; allowed: an array of 2 numbers, each >= -1e+06"));
    // Beyond 4000 elements in all double precision cannot resolve the lowest modes (schema.cpp, kMaxElements).
    s = beam(3000);
    set(s, "members", Value(Value::Array{table({{"start", vec(0, 0)}, {"end", vec(L, 0)}, {"n_elements", Value(3000)}}),
                                         table({{"start", vec(L, 0)}, {"end", vec(2 * L, 0)}, {"n_elements", Value(2000)}})}));
    CHECK(mentions(problem(s), "key 'structure.members': 5000 elements in all; allowed: at most 4000"));
    // 1e300 steps per period used to pass and then fail blaming time.dt_max.
    s = beam(10);
    set(s, "time.steps_per_period", Value(1e300));
    CHECK(mentions(problem(s), "key 'structure.time.steps_per_period'"));
}

TEST_CASE("supports and point loads must sit on nodes") {
    Value s = beam(10);
    set(s, "supports", Value(Value::Array{table({{"at", vec(0.05, 0)}, {"type", Value("pinned")}})}));
    CHECK(mentions(problem(s), "structure.supports[0].at"));
    s = beam(10);
    set(s, "point_loads", Value(Value::Array{point_load(0.3, 0.0, 0, -1)}));
    CHECK(problem(s).empty());  // node 3 of 10
    set(s, "point_loads", Value(Value::Array{point_load(0.35, 0.0, 0, -1)}));
    CHECK(mentions(problem(s), "structure.point_loads[0].at"));
    s = beam(10);
    set(s, "initial.preload", Value(Value::Array{point_load(0.35, 0.0, 0, -1)}));
    CHECK(mentions(problem(s), "structure.initial.preload[0].at"));
}

TEST_CASE("a support or load where two members cross without a joint is refused, naming both") {
    // Interior nodes of crossing members stay apart (members join at their ends): a support there held one
    // member and the other fell freely (a review, 2026-11-28). Where a member ends, the nodes are one joint.
    Value s = beam(2);
    s.as_table_mut()["members"] = Value(Value::Array{
        table({{"start", vec(-1, 0)}, {"end", vec(1, 0)}, {"n_elements", Value(2)}}),
        table({{"start", vec(0, -1)}, {"end", vec(0, 1)}, {"n_elements", Value(2)}})});
    set(s, "supports", Value(Value::Array{table({{"at", vec(0, 0)}, {"type", Value("clamped")}})}));
    const std::string why = problem(s);
    CHECK(mentions(why, "structure.supports[0].at"));
    CHECK(mentions(why, "members[0] and members[1] cross"));
    set(s, "supports", Value(Value::Array{table({{"at", vec(-1, 0)}, {"type", Value("clamped")}})}));
    set(s, "point_loads", Value(Value::Array{point_load(0, 0, 0, -1)}));
    CHECK(mentions(problem(s), "structure.point_loads[0].at"));
    // Ended there, the second member is joined: one node, no question which.
    s.as_table_mut()["members"].as_array_mut()[1] = table({{"start", vec(0, 0)}, {"end", vec(0, 1)}, {"n_elements", Value(1)}});
    CHECK(problem(s) == "");
}

TEST_CASE("a member whose elements are no longer than the node tolerance is refused, naming it") {
    // 5e-7 m beside a 1 m member: both ends one node (tolerance 1e-6 m); the participant had refused it with no
    // scene line, as "elements of length 0.000000 m" (a review, 2026-11-28).
    Value s = beam(10);
    s.as_table_mut()["members"].as_array_mut().push_back(
        table({{"start", vec(L, 0)}, {"end", vec(L, 5e-7)}, {"n_elements", Value(1)}}));
    const std::string why = problem(s);
    CHECK(mentions(why, "structure.members[1]': 1 elements of 5e-07 m; allowed: elements longer than 1e-06 m"));
}

TEST_CASE("cross-key rules: members, distributed loads, damping, initial state, load times") {
    Value s = beam(10);
    set(s, "members", Value(Value::Array{table({{"start", vec(0, 0)}, {"end", vec(0, 0)}})}));
    CHECK(mentions(problem(s), "a member needs length > 0"));

    s = beam(10);  // a post whose foot lands between two nodes of the beam is not connected
    auto& members = s.as_table_mut()["members"].as_array_mut();
    members.push_back(table({{"start", vec(0.55, 0)}, {"end", vec(0.55, 0.5)}}));
    CHECK(mentions(problem(s), "between two of its nodes"));
    members.back() = table({{"start", vec(0.5, 0)}, {"end", vec(0.5, 0.5)}});
    CHECK(problem(s).empty());

    s = beam(10);
    set(s, "distributed_loads", Value(Value::Array{table({{"member", Value(1)}, {"q", vec(0, -1)}})}));
    CHECK(mentions(problem(s), "structure.distributed_loads[0].member"));

    s = beam(10);
    set(s, "damping.model", Value("rayleigh"));
    set(s, "damping.frequencies", vec(10, 5));
    CHECK(mentions(problem(s), "f1 < f2"));

    s = beam(10);
    set(s, "initial.mode", Value(1));
    set(s, "initial.static_equilibrium", Value(true));
    CHECK(mentions(problem(s), "exclude each other"));

    s = beam(10);
    Value load = point_load(1, 0, 0, -1);
    set(load, "start_time", Value(1.0));
    set(load, "end_time", Value(0.5));
    set(s, "point_loads", Value(Value::Array{load}));
    CHECK(mentions(problem(s), "end_time"));

    s = beam(10, "clamped", "pinned");
    set(s, "supports", Value(Value::Array{table({{"at", vec(0, 0)}, {"type", Value("pinned")}}),
                                          table({{"at", vec(0, 0)}, {"type", Value("roller")}})}));
    CHECK(mentions(problem(s), "one support per node"));
}

TEST_CASE("the key reference documents every key with a meaning") {
    const std::string doc = scene_schema().document("structure");
    for (const char* key : {"structure.formulation", "structure.material.E", "structure.section.depth",
                            "structure.members[].n_elements", "structure.supports[].normal",
                            "structure.point_loads[].history", "structure.distributed_loads[].q",
                            "structure.damping.frequencies", "structure.time.rho_inf", "structure.newton.tolerance",
                            "structure.initial.preload[].at"})
        CHECK_MESSAGE(mentions(doc, std::string("`") + key + "`"), key);
}
}
