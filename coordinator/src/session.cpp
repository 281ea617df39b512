#include "sphfsi/coordinator/session.hpp"

#include <cmath>

namespace sphfsi::coordinator {
using namespace sphfsi::protocol;
using Clock = std::chrono::steady_clock;

std::uint64_t Session::start_advance(const std::string& role, double t, double dt, std::uint32_t substeps,
                                     std::uint32_t iteration, Fields inputs) {
    started_[role] = Clock::now();
    return hub_.send(role, MessageType::Advance, AdvanceRequest{t, dt, substeps, iteration, std::move(inputs)});
}

StepResult Session::finish_advance(const std::string& role, std::uint64_t seq) {
    Message m = hub_.await_reply(role, seq);
    if (m.type != MessageType::Advanced)
        throw ParticipantFailure(role, "garbage", "answered ADVANCE with " + std::string(to_string(m.type)));
    StepResult r{m.as<AdvanceReply>(), std::chrono::duration<double>(Clock::now() - started_[role]).count()};
    if (!(r.reply.dt_wanted > 0) || !std::isfinite(r.reply.dt_wanted))
        throw ParticipantFailure(role, "garbage", "wants a step of " + std::to_string(r.reply.dt_wanted) + " s");
    return r;
}

void Session::save(const std::string& role) {
    if (hub_.request(role, MessageType::Save).type != MessageType::Ack)
        throw ParticipantFailure(role, "garbage", "did not ACK SAVE");
}

void Session::restore(const std::string& role) {
    if (hub_.request(role, MessageType::Restore).type != MessageType::Ack)
        throw ParticipantFailure(role, "garbage", "did not ACK RESTORE");
}

void InterfaceState::reset(const InterfaceMesh& m) {
    mesh = m;
    const auto n = m.vertices.rows();
    displacement = velocity = previous_displacement = force = fluid_displacement = F64Array::zeros(n, 2);
    previous_dt = 0.0;
    work_total = created_total = fluid_energy = total_energy = 0.0;
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
