#include "sphfsi/coordinator/session.hpp"

#include <limits>
#include <cmath>

#include "sphfsi/coordinator/recorder.hpp"
#include "sphfsi/protocol/codec.hpp"

namespace sphfsi::coordinator {
using namespace sphfsi::protocol;
using Clock = std::chrono::steady_clock;

std::uint64_t Session::start_advance(const std::string& role, double t, double dt, std::uint32_t substeps,
                                     std::uint32_t iteration, Fields inputs) {
    asked_[role] = Asked{t, dt, substeps};
    return hub_.send(role, MessageType::Advance, AdvanceRequest{t, dt, substeps, iteration, std::move(inputs)});
}

StepResult Session::finish_advance(const std::string& role, std::uint64_t seq) {
    // The round trip ends when the reply arrived: under parallel-explicit the structure's is collected after
    // the fluid's, and timing it here counted the fluid's compute time as the structure's messaging.
    double roundtrip = 0.0;
    Message m = hub_.await_reply(role, seq, &roundtrip);
    const Asked& asked = asked_.at(role);
    StepResult r{m.as<AdvanceReply>(), roundtrip};
    // The reply must say it did what was asked: the coordinator's clock and records go by the request.
    const double end = asked.t + asked.dt;
    if (!same_instant(r.reply.t, end, asked.dt))
        throw ParticipantFailure(role, "garbage", "reports reaching t = " + seconds(r.reply.t) + ", but the window ends at t = " + seconds(end));
    if (asked.substeps > 0 ? r.reply.substeps != asked.substeps : r.reply.substeps == 0)
        throw ParticipantFailure(role, "garbage", "reports " + std::to_string(r.reply.substeps) + " sub-steps, asked for " +
                                                      (asked.substeps > 0 ? std::to_string(asked.substeps) : "at least 1"));
    if (!(r.reply.dt_wanted > 0) || !std::isfinite(r.reply.dt_wanted))
        throw ParticipantFailure(role, "garbage", "wants a step of " + seconds(r.reply.dt_wanted));
    if (!(r.reply.compute_s >= 0) || !std::isfinite(r.reply.compute_s))
        throw ParticipantFailure(role, "garbage", "reports a compute time of " + seconds(r.reply.compute_s));
    // Each becomes the window column ROLE.NAME in the record.
    if (r.reply.stats.is_table()) {
        if (r.reply.stats.as_table().size() > kMaxStats)
            throw ParticipantFailure(role, "garbage", "reports " + std::to_string(r.reply.stats.as_table().size()) +
                                                          " stats; at most " + std::to_string(kMaxStats));
        for (const auto& [name, value] : r.reply.stats.as_table()) {
            if (!plain_name(name))
                throw ParticipantFailure(role, "garbage", "reports stats '" + printable(name) +
                                                              "', which is not a plain name (" + kPlainNameRule + ")");
            if (!value.is_number())
                throw ParticipantFailure(role, "garbage", "reports stats '" + name + "' that is not a number (ADVANCED stats: str -> number)");
            // A NaN kinetic_energy would silently switch the energy checks off; any non-finite stat is a
            // participant that blew up without saying so.
            if (!std::isfinite(value.as_double()))
                throw ParticipantFailure(role, "garbage", "reports stats '" + name + "' = " + std::to_string(value.as_double()) +
                                                              ", not a finite number");
        }
    }
    return r;
}

void Session::save(const std::string& role) { hub_.request(role, MessageType::Save); }

void Session::restore(const std::string& role) { hub_.request(role, MessageType::Restore); }

void InterfaceState::reset(const InterfaceMesh& m) {
    mesh = m;
    const auto n = m.vertices.rows();
    displacement = velocity = previous_displacement = force = fluid_displacement = F64Array::zeros(n, 2);
    previous_dt = 0.0;
    work_total = created_total = fluid_energy = 0.0;
    total_energy = std::numeric_limits<double>::quiet_NaN();
    secants.clear();
}

const F64Array& vertex_field(const std::string& role, const Fields& fields, const std::string& name, std::size_t vertices) {
    auto it = fields.find(name);
    if (it == fields.end()) throw ParticipantFailure(role, "garbage", "did not send the output '" + name + "'");
    const auto* a = std::get_if<F64Array>(&it->second);
    if (!a || a->shape != std::vector<std::uint64_t>{vertices, 2})
        throw ParticipantFailure(role, "garbage", "sent '" + name + "' that is not f8 of shape [" + std::to_string(vertices) + ", 2]");
    for (double x : a->values)
        if (!std::isfinite(x)) throw ParticipantFailure(role, "diverged", "sent a non-finite value in '" + name + "'");
    return *a;
}

}  // namespace sphfsi::coordinator
