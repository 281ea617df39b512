#include "sphfsi/coordinator/hub.hpp"

#include <algorithm>
#include <chrono>
#include <thread>

#include "sphfsi/protocol/codec.hpp"

namespace sphfsi::coordinator {
using namespace sphfsi::protocol;
using Clock = std::chrono::steady_clock;

volatile std::sig_atomic_t g_interrupted = 0;

namespace {
// The largest first message taken from an unknown connection (docs/protocol.md, "Limits"): a HELLO is
// under 1 KiB.
constexpr std::size_t kLargestStrangerMessage = 64 * 1024;
double seconds_since(Clock::time_point t) { return std::chrono::duration<double>(Clock::now() - t).count(); }
ParticipantFailure reported(const std::string& role, const ErrorReply& e) {
    return ParticipantFailure(role, e.code, "reported " + printable(e.code) + ": " + printable(e.message, 2000));
}
std::string fmt_s(double s) {
    char buf[32];
    std::snprintf(buf, sizeof buf, "%.1f s", s);
    return buf;
}
}  // namespace

Hub::Hub(std::string bind_endpoint, std::string token, HubTiming timing, Launcher* launcher, Log log)
    : ctx_(1), socket_(ctx_, zmq::socket_type::router), token_(std::move(token)), timing_(timing),
      launcher_(launcher), log_(std::move(log)) {
    socket_.set(zmq::sockopt::linger, 0);
    socket_.set(zmq::sockopt::router_mandatory, 1);  // sending to a vanished peer is an error, not a silent drop
    socket_.set(zmq::sockopt::maxmsgsize, static_cast<int64_t>(DecodeLimits{}.max_bytes));
    // With router_mandatory a send to a peer whose queue is full blocks: bounded, so nothing waits for ever.
    socket_.set(zmq::sockopt::sndtimeo, static_cast<int>(std::max(1.0, 1000.0 * timing_.timeout_s)));
    socket_.bind(bind_endpoint);
    endpoint_ = socket_.get(zmq::sockopt::last_endpoint);
    last_beat_sent_ = Clock::now();
}

void Hub::send_raw(const std::string& identity, const Message& m, bool droppable) {
    auto start = Clock::now();
    std::string bytes = encode(m);
    const auto role = identity_role_.find(identity);
    bool taken = false;
    try {
        const auto more = droppable ? zmq::send_flags::sndmore | zmq::send_flags::dontwait : zmq::send_flags::sndmore;
        const auto last = droppable ? zmq::send_flags::dontwait : zmq::send_flags::none;
        taken = socket_.send(zmq::buffer(identity), more) && socket_.send(zmq::buffer(bytes), last);
    } catch (const zmq::error_t& e) {
        // A send blocks only on a full queue (router_mandatory); a Ctrl-C then wakes it with EINTR. That is the
        // user's stop, not the participant's death. The blocking frame is the identity, the first, so no
        // half-sent message is left behind on the socket.
        if (e.num() == EINTR && g_interrupted) throw Interrupted();
        if (role != identity_role_.end()) {
            // A participant killed a moment ago is unreachable before its exit is reaped, and its exit ("was
            // killed by signal 9") says more than "Host unreachable" did (a kill probe, 2026-11-28): the exit is
            // waited for, briefly.
            for (const auto until = Clock::now() + std::chrono::milliseconds(500); launcher_ && !closing_ && Clock::now() < until;) {
                if (auto exited = launcher_->poll_exited()) report_exit(exited->first, exited->second);
                std::this_thread::sleep_for(std::chrono::milliseconds(10));
            }
            throw ParticipantFailure(role->second, "died", "cannot be reached: " + std::string(e.what()));
        }
        // a stranger that went away: nothing to do
    }
    if (!taken && !droppable && role != identity_role_.end())
        throw ParticipantFailure(role->second, "hung", "has not taken a message for " + fmt_s(timing_.timeout_s) +
                                                           " (it reads none: its queue is full; run.timeout_s)");
    messaging_s_ += seconds_since(start);
}

const std::string& Hub::identity_of(const std::string& role) const {
    auto it = role_identity_.find(role);
    if (it == role_identity_.end()) throw std::logic_error("no participant for role " + role);
    return it->second;
}

std::uint64_t Hub::send(const std::string& role, MessageType type, Body body) {
    Message m = make_message(type, ++seq_, token_, std::move(body));
    m.version = peers_.at(role).version;
    send_raw(identity_of(role), m);
    open_[role][m.seq] = OpenRequest{type, Clock::now()};
    return m.seq;
}

Message Hub::await_reply(const std::string& role, std::uint64_t seq, double* roundtrip_s) {
    while (true) {
        auto& box = inbox_[role];
        if (auto it = box.find(seq); it != box.end()) {
            Message m = std::move(it->second.message);
            if (roundtrip_s) *roundtrip_s = it->second.roundtrip_s;
            box.erase(it);
            if (m.type == MessageType::Error) throw reported(role, m.as<ErrorReply>());
            return m;
        }
        pump(50);
    }
}

void Hub::await_hellos(const std::vector<std::string>& roles) {
    expected_ = roles;
    auto start = Clock::now();
    while (true) {
        bool all = std::all_of(roles.begin(), roles.end(), [&](const std::string& r) { return peers_.count(r) > 0; });
        if (all) return;
        if (seconds_since(start) > timing_.startup_timeout_s)
            for (const auto& r : roles)
                if (!peers_.count(r))
                    throw ParticipantFailure(r, "died", "did not connect within " + fmt_s(timing_.startup_timeout_s) +
                                                            " (run.startup_timeout_s)");
        pump(50);
    }
}

void Hub::goodbye(double timeout_s) {
    closing_ = true;  // exits are expected now: the launcher reaps them and reports any unclean one
    std::map<std::string, std::uint64_t> pending;
    for (const auto& [role, peer] : peers_) {
        try {
            pending[role] = send(role, MessageType::Bye);
        } catch (const std::exception&) {
        }
    }
    auto start = Clock::now();
    while (!pending.empty() && seconds_since(start) < timeout_s) {
        try {
            pump(20, false);  // after Ctrl-C too: the ACKs are still worth reading
        } catch (const std::exception&) {
            // a participant that exits right after its ACK, or misbehaves now, changes nothing
        }
        for (auto it = pending.begin(); it != pending.end();) {
            auto& box = inbox_[it->first];
            if (box.count(it->second)) it = pending.erase(it);
            else ++it;
        }
    }
    peers_.clear();
}

void Hub::pump(int wait_ms, bool interruptible) {
    wait_for_input(wait_ms, interruptible);
    receive_all();
    check_liveness();
}

void Hub::wait_for_input(int wait_ms, bool interruptible) {
    if (interruptible && g_interrupted) throw Interrupted();
    zmq::pollitem_t item{socket_.handle(), 0, ZMQ_POLLIN, 0};
    try {
        zmq::poll(&item, 1, std::chrono::milliseconds(wait_ms));
    } catch (const zmq::error_t& e) {
        if (e.num() != EINTR) throw;
        if (interruptible && g_interrupted) throw Interrupted();  // a signal woke us: SIGINT/SIGTERM asks to stop
    }
}

void Hub::receive_all() {
    while (true) {
        zmq::message_t identity, payload;
        if (!socket_.recv(identity, zmq::recv_flags::dontwait)) break;
        if (!identity.more()) continue;  // cannot happen on a ROUTER; ignore defensively
        (void)socket_.recv(payload, zmq::recv_flags::dontwait);
        bool multipart = payload.more();
        while (payload.more()) {  // drain extra frames of a multipart message
            zmq::message_t extra;
            if (!socket_.recv(extra, zmq::recv_flags::dontwait)) break;
            if (!extra.more()) break;
        }
        std::string id(static_cast<const char*>(identity.data()), identity.size());
        auto known = identity_role_.find(id);
        if (known == identity_role_.end()) {
            handle_stranger(id, payload, multipart);
            continue;
        }
        const std::string& role = known->second;
        // An ERROR back carries the version agreed at WELCOME, as every message after it (docs/protocol.md 3.1).
        auto error_reply = [&](std::uint64_t seq, const std::string& code, const std::string& why) {
            Message e = make_message(MessageType::Error, seq, token_, ErrorReply{code, why, seq});
            e.version = peers_.at(role).version;
            send_raw(id, e);
        };
        auto start = Clock::now();
        Message m;
        try {
            if (multipart) throw ProtocolError("bad_message", "message has more than one frame");
            m = decode(payload.data(), payload.size());
        } catch (const ProtocolError& e) {
            if (e.answerable())  // a malformed HEARTBEAT or ERROR is not answered (docs/protocol.md, "Errors")
                error_reply(e.seq(), e.code(), e.what());
            throw ParticipantFailure(role, "garbage", "sent a malformed message (" + e.code() + "): " + e.what());
        }
        messaging_s_ += seconds_since(start);
        // Refused as docs/protocol.md says (answered unless HEARTBEAT or ERROR), then fatal: a welcomed
        // participant that changes token or version mid-run is broken.
        auto refusal = [&](const std::string& code, const std::string& why) {
            if (is_answered(m.type)) error_reply(m.seq, code, why);
            return ParticipantFailure(role, "garbage", why);
        };
        if (m.token != token_) throw refusal("bad_token", "sent a message with a wrong token");
        PeerInfo& peer = peers_[role];
        if (m.version != peer.version)
            throw refusal("version_mismatch", "switched protocol version to " + std::to_string(m.version));
        peer.last_seen = Clock::now();
        if (m.type == MessageType::Heartbeat) {
            const std::uint64_t progress = m.as<Heartbeat>().progress;
            if (progress != peer.progress) peer.progress_moved = peer.last_seen;
            peer.progress = progress;
            continue;
        }
        file_reply(role, std::move(m));
    }
}

// Every message but a HEARTBEAT must answer a request this hub sent the participant and has not had an
// answer to, with that request's reply type or ERROR. Anything else (a wrong or repeated seq, a reply sent
// ahead of its request, the wrong reply type) would otherwise wait in the inbox for ever, or be taken as the
// answer to a later request: both are named as garbage at once.
void Hub::file_reply(const std::string& role, Message m) {
    auto& open = open_[role];
    auto request = open.find(m.seq);
    if (request == open.end()) {
        // e.g. seq 0: it could not read our request; its words still count
        if (m.type == MessageType::Error) throw reported(role, m.as<ErrorReply>());
        std::string open_list;
        for (const auto& [seq, r] : open) open_list += (open_list.empty() ? "" : ", ") + std::string(to_string(r.type)) + " " + std::to_string(seq);
        throw ParticipantFailure(role, "garbage", "sent " + std::string(to_string(m.type)) + " with seq " + std::to_string(m.seq) +
                                                      ", which answers no open request (open: " +
                                                      (open_list.empty() ? "none" : open_list) + ")");
    }
    const MessageType expected = expected_reply(request->second.type);
    if (m.type != expected && m.type != MessageType::Error)
        throw ParticipantFailure(role, "garbage", "answered " + std::string(to_string(request->second.type)) + " (seq " +
                                                      std::to_string(m.seq) + ") with " + std::string(to_string(m.type)) +
                                                      ", not " + std::string(to_string(expected)));
    const double roundtrip = seconds_since(request->second.sent);
    open.erase(request);
    const std::uint64_t seq = m.seq;
    inbox_[role].insert_or_assign(seq, Reply{std::move(m), roundtrip});
}

void Hub::handle_stranger(const std::string& id, const zmq::message_t& payload, bool multipart) {
    // A refusal echoes the stranger's own token (empty when unreadable), never this run's: the run token is
    // the only thing keeping another local process from joining, so it must not be handed out on request.
    std::string their_token;
    std::uint32_t their_version = kOldestSupportedVersion;  // a refusal in the stranger's own version if we speak it
    auto refuse = [&](std::uint64_t seq, const std::string& code, const std::string& why) {
        log_("refused a connection: " + why);
        Message e = make_message(MessageType::Error, seq, their_token, ErrorReply{code, why, seq});
        e.version = their_version;
        send_raw(id, e, true);
    };
    // A stranger's first words are a HELLO, well under 1 KiB; anything much larger is refused unread, so that
    // a local process without the token cannot keep this thread (and the heartbeats) busy decoding.
    DecodeLimits stranger_limits;
    stranger_limits.max_bytes = kLargestStrangerMessage;
    Message m;
    try {
        m = decode(payload.data(), payload.size(), stranger_limits);
    } catch (const ProtocolError& e) {
        if (!e.answerable()) return log_("ignored a malformed " + e.type_name() + " from an unknown connection");
        return refuse(e.seq(), e.code(), std::string("malformed first message: ") + e.what());
    }
    their_token = m.token;
    if (m.version >= kOldestSupportedVersion && m.version <= kProtocolVersion) their_version = m.version;
    if (!is_answered(m.type)) {  // once per connection: a stray peer's heartbeats would fill the log
        if (quiet_strangers_.insert(id).second)
            log_("ignored " + std::string(to_string(m.type)) + " from an unknown connection (further ones not logged)");
        if (m.type == MessageType::Heartbeat && m.token == token_) stray_heartbeats_ = true;
        return;
    }
    // One frame a message (docs/protocol.md 1), from the first on: after WELCOME a second frame ends the run.
    if (multipart) return refuse(m.seq, "bad_message", "message has more than one frame");
    if (m.type != MessageType::Hello) return refuse(m.seq, "refused", "first message must be HELLO, got " + std::string(to_string(m.type)));
    if (m.token != token_) return refuse(m.seq, "bad_token", "HELLO carries a token that is not this run's (stale or stray participant)");
    const auto& h = m.as<Hello>();
    std::uint32_t lo = std::max(h.version_min, kOldestSupportedVersion), hi = std::min(h.version_max, kProtocolVersion);
    if (lo > hi)
        return refuse(m.seq, "version_mismatch",
                      "participant '" + printable(h.name) + "' speaks protocol " + std::to_string(h.version_min) + ".." +
                          std::to_string(h.version_max) + ", the coordinator " + std::to_string(kOldestSupportedVersion) +
                          ".." + std::to_string(kProtocolVersion));
    if (std::find(expected_.begin(), expected_.end(), h.name) == expected_.end())
        return refuse(m.seq, "refused", "the scene has no participant named '" + printable(h.name) + "'");
    if (peers_.count(h.name)) return refuse(m.seq, "refused", "'" + h.name + "' is already connected");
    // A role is what the scene needs and the kind what the program is; the roles are named after the kinds.
    if (h.kind != h.name)
        return refuse(m.seq, "refused", "'" + printable(h.name) + "' says it is a " + printable(h.kind) +
                                            " program (HELLO kind); the role needs a " + printable(h.name));
    identity_role_[id] = h.name;
    role_identity_[h.name] = id;
    PeerInfo& p = peers_[h.name];
    p.role = h.name;
    p.software = h.software;
    p.pid = h.pid;
    p.version = hi;
    p.last_seen = Clock::now();
    Message w = make_message(MessageType::Welcome, m.seq, token_, Welcome{hi, timing_.heartbeat_s, timing_.timeout_s});
    w.version = hi;
    send_raw(id, w);
    log_(h.name + " connected: " + printable(h.software, 200) + " (pid " + std::to_string(h.pid) + ", protocol " + std::to_string(hi) + ")");
}

// A participant that reports an ERROR and exits (as a script ending in sys.exit(1) does) is reported by its
// ERROR, which says what went wrong, not by its exit: the ERROR may reach us a moment after the exit, so the
// socket is read for a little longer first.
void Hub::report_exit(const std::string& role, const std::string& how) {
    const auto until = Clock::now() + std::chrono::milliseconds(500);  // (a loaded machine delivers late)
    while (Clock::now() < until) {
        for (const auto& [seq, reply] : inbox_[role])
            if (reply.message.type == MessageType::Error) throw reported(role, reply.message.as<ErrorReply>());
        wait_for_input(20, false);
        receive_all();
    }
    throw ParticipantFailure(role, "died", how);
}

void Hub::check_liveness() {
    if (launcher_ && !closing_)
        if (auto exited = launcher_->poll_exited()) report_exit(exited->first, exited->second);
    for (const auto& [role, peer] : peers_) {
        double silent = seconds_since(peer.last_seen);
        if (silent > timing_.timeout_s)
            throw ParticipantFailure(role, "hung", "has been silent for " + fmt_s(silent) +
                                                       " (no reply, no heartbeat; run.timeout_s = " + fmt_s(timing_.timeout_s) + ")" +
                                                       // The likely cause when this run's token came from another socket.
                                                       (stray_heartbeats_ ? "; HEARTBEATs with this run's token came from a "
                                                                            "connection that never said HELLO: a participant must "
                                                                            "send them on the socket that said HELLO (docs/protocol.md 3.3)"
                                                                          : ""));
        // Heartbeats prove the process lives, not that it computes: during an ADVANCE its sub-step count
        // must move; any other request (INIT, SNAPSHOT, CHECKPOINT, SAVE, RESTORE: no sub-steps) must be
        // answered within the same time.
        for (const auto& [seq, request] : open_[role]) {
            if (request.type == MessageType::Bye) continue;  // goodbye() bounds its own wait
            const bool advance = request.type == MessageType::Advance;
            double stalled = seconds_since(advance ? std::max(request.sent, peer.progress_moved) : request.sent);
            if (stalled <= timing_.stall_timeout_s) continue;
            const std::string limit = "; run.stall_timeout_s = " + fmt_s(timing_.stall_timeout_s) + ")";
            if (advance)
                throw ParticipantFailure(role, "hung", "has taken no sub-step for " + fmt_s(stalled) + " of an ADVANCE while its heartbeats go on " +
                                                           "(progress stuck at " + std::to_string(peer.progress) + limit);
            throw ParticipantFailure(role, "hung", "has not answered " + std::string(to_string(request.type)) + " for " + fmt_s(stalled) +
                                                       " while its heartbeats go on (" + limit.substr(2));
        }
    }
    if (seconds_since(last_beat_sent_) >= timing_.heartbeat_s) {
        last_beat_sent_ = Clock::now();
        for (const auto& [role, peer] : peers_) {
            // Their own counter (docs/protocol.md §2): request numbers stay 1, 2, 3, ... per run.
            Message m = make_message(MessageType::Heartbeat, ++beat_seq_, token_, Heartbeat{0});
            m.version = peer.version;
            send_raw(identity_of(role), m, true);
        }
    }
}

}  // namespace sphfsi::coordinator
