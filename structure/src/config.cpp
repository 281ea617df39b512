#include "sphfsi/structure/config.hpp"

#include <algorithm>
#include <cmath>
#include <numbers>

#include "sphfsi/structure/schema.hpp"

namespace sphfsi::structure {
namespace {

Point2 point(const Value& v) {
    auto d = v.as_doubles();
    return {d.at(0), d.at(1)};
}

History history(const Value& t) {
    History h;
    const std::string& kind = t.at("history").as_string();
    h.kind = kind == "ramp" ? History::Kind::Ramp : kind == "sine" ? History::Kind::Sine : History::Kind::Constant;
    h.ramp_time = t.at("ramp_time").as_double();
    h.frequency = t.at("frequency").as_double();
    h.phase = t.at("phase").as_double();
    h.start_time = t.at("start_time").as_double();
    if (const Value* e = t.find("end_time")) h.end_time = e->as_double();
    return h;
}

PointLoadSpec point_load(const Value& t) {
    PointLoadSpec p;
    p.at = point(t.at("at"));
    p.force = point(t.at("force"));
    p.moment = t.at("moment").as_double();
    if (t.contains("history")) p.history = history(t);
    return p;
}

template <class F>
void each(const Value& table, const char* key, F&& f) {
    if (const Value* a = table.find(key))
        for (const Value& v : a->as_array()) f(v);
}

}  // namespace

double History::factor(double t, Side side) const {
    const bool off = side == Side::Right ? (t < start_time || (end_time && t >= *end_time))
                                         : (t <= start_time || (end_time && t > *end_time));
    if (off) return 0.0;
    const double s = t - start_time;
    switch (kind) {
        case Kind::Constant: return 1.0;
        case Kind::Ramp: return std::min(s / ramp_time, 1.0);
        case Kind::Sine: return std::sin(2.0 * std::numbers::pi * frequency * s + phase);
    }
    return 0.0;
}

double History::mean_factor(double t0, double t1) const {
    const double a = std::max(t0, start_time) - start_time;
    const double b = std::min(t1, end_time.value_or(t1)) - start_time;
    if (!(b > a)) return 0.0;
    double integral = 0.0;
    switch (kind) {
        case Kind::Constant: integral = b - a; break;
        case Kind::Ramp: {
            // The ramp's antiderivative: s^2 / (2 T) up to T, then T / 2 + (s - T).
            const double T = ramp_time;
            const auto F = [T](double s) { return s < T ? s * s / (2.0 * T) : 0.5 * T + (s - T); };
            integral = F(b) - F(a);
            break;
        }
        case Kind::Sine: {
            // cos(w a + phase) - cos(w b + phase), as a product: no cancellation when w (b - a) is small.
            const double w = 2.0 * std::numbers::pi * frequency;
            integral = 2.0 * std::sin(0.5 * w * (a + b) + phase) * std::sin(0.5 * w * (b - a)) / w;
            break;
        }
    }
    return integral / (t1 - t0);
}

StructureConfig StructureConfig::from_value(const Value& section) {
    const Value s = validated_config(section);
    StructureConfig c;
    c.formulation = s.at("formulation").as_string() == "corotational" ? Formulation::Corotational : Formulation::Linear;
    c.mass = s.at("mass").as_string() == "lumped" ? MassKind::Lumped : MassKind::Consistent;
    c.gravity = s.at("gravity").as_bool();
    c.gravity_vector = point(s.at("gravity_vector"));

    const Value& m = s.at("material");
    c.material = {m.at("E").as_double(), m.at("nu").as_double(), m.at("rho").as_double()};
    const Value& sec = s.at("section");
    c.section = {sec.at("thickness").as_double(), sec.at("depth").as_double(), sec.at("plane_strain").as_bool()};

    each(s, "members", [&](const Value& v) {
        MemberSpec ms;
        if (const Value* n = v.find("name")) ms.name = n->as_string();
        ms.start = point(v.at("start"));
        ms.end = point(v.at("end"));
        ms.n_elements = static_cast<int>(v.at("n_elements").as_int());
        ms.wetted = v.at("wetted").as_bool();
        const auto padding = v.at("interface_padding").as_doubles();
        ms.pad_left = padding[0];
        ms.pad_right = padding[1];
        c.members.push_back(ms);
    });
    each(s, "supports", [&](const Value& v) {
        SupportSpec sp;
        sp.at = point(v.at("at"));
        const std::string& type = v.at("type").as_string();
        sp.type = type == "clamped" ? SupportType::Clamped
                  : type == "pinned" ? SupportType::Pinned
                  : type == "roller" ? SupportType::Roller
                                     : SupportType::Free;
        sp.normal = point(v.at("normal"));
        c.supports.push_back(sp);
    });
    each(s, "point_loads", [&](const Value& v) { c.point_loads.push_back(point_load(v)); });
    each(s, "distributed_loads", [&](const Value& v) {
        c.distributed_loads.push_back({static_cast<int>(v.at("member").as_int()), point(v.at("q")), history(v)});
    });

    const Value& d = s.at("damping");
    const std::string& dk = d.at("model").as_string();
    c.damping.kind = dk == "simple" ? DampingKind::Simple : dk == "rayleigh" ? DampingKind::Rayleigh : DampingKind::None;
    c.damping.c = d.at("c").as_double();
    c.damping.ratios = point(d.at("ratios"));
    if (const Value* f = d.find("frequencies")) c.damping.frequencies = point(*f);

    const Value& t = s.at("time");
    const std::string& ik = t.at("integrator").as_string();
    c.time.integrator = ik == "backward_euler" ? IntegratorKind::BackwardEuler
                        : ik == "newmark"     ? IntegratorKind::Newmark
                                              : IntegratorKind::GeneralizedAlpha;
    c.time.rho_inf = t.at("rho_inf").as_double();
    c.time.dt_max = t.at("dt_max").as_double();
    c.time.resolved_modes = static_cast<int>(t.at("resolved_modes").as_int());
    c.time.steps_per_period = t.at("steps_per_period").as_double();
    c.time.max_numerical_damping = t.at("max_numerical_damping").as_double();

    c.failure.max_energy_created = s.at("failure").at("max_energy_created").as_double();
    const Value& n = s.at("newton");
    c.newton = {n.at("tolerance").as_double(), static_cast<int>(n.at("max_iterations").as_int()),
                static_cast<int>(n.at("load_steps").as_int())};

    const Value& i = s.at("initial");
    c.initial.static_equilibrium = i.at("static_equilibrium").as_bool();
    c.initial.mode = static_cast<int>(i.at("mode").as_int());
    c.initial.mode_amplitude = i.at("mode_amplitude").as_double();
    each(i, "preload", [&](const Value& v) { c.initial.preload.push_back(point_load(v)); });
    return c;
}

}  // namespace sphfsi::structure
