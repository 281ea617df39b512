#pragma once
// The coordinator's end of the wire: one ROUTER socket, the welcomed participants, their liveness.
// Every wait in here is bounded: a participant that dies, hangs or talks garbage becomes a
// ParticipantFailure naming it within the scene's timeout; strays are refused and logged, never fatal.
#include <chrono>
#include <csignal>
#include <functional>
#include <map>
#include <optional>
#include <set>
#include <stdexcept>
#include <string>
#include <vector>
#include <zmq.hpp>

#include "sphfsi/coordinator/launcher.hpp"
#include "sphfsi/protocol/message.hpp"

namespace sphfsi::coordinator {

class ParticipantFailure : public std::runtime_error {
public:
    ParticipantFailure(std::string role, std::string code, const std::string& what)
        : std::runtime_error(role + " " + what), role_(std::move(role)), code_(std::move(code)) {}
    const std::string& role() const { return role_; }
    const std::string& code() const { return code_; }  // protocol error code, or "died", "hung", "garbage"

private:
    std::string role_, code_;
};

// Thrown when SIGINT/SIGTERM asked the run to stop.
class Interrupted : public std::runtime_error {
public:
    Interrupted() : std::runtime_error("interrupted by signal") {}
};
extern volatile std::sig_atomic_t g_interrupted;

struct HubTiming {
    double heartbeat_s = 0.5;
    double timeout_s = 3.0;
    double startup_timeout_s = 10.0;
    // A participant whose heartbeats go on but whose sub-step count stands still this long during an
    // ADVANCE is stuck (a deadlock or endless loop beside a live heartbeat thread): run.stall_timeout_s.
    double stall_timeout_s = 30.0;
};

struct PeerInfo {
    std::string role, software;
    std::int64_t pid = 0;
    std::uint32_t version = 0;  // protocol version negotiated with this participant
    std::uint64_t progress = 0;
    std::chrono::steady_clock::time_point last_seen;
    std::chrono::steady_clock::time_point progress_moved;  // when `progress` last changed
};

class Hub {
public:
    using Log = std::function<void(const std::string&)>;
    Hub(std::string bind_endpoint, std::string token, HubTiming timing, Launcher* launcher, Log log);

    const std::string& endpoint() const { return endpoint_; }
    const std::string& token() const { return token_; }

    // Waits until every role has said a valid HELLO and was welcomed.
    void await_hellos(const std::vector<std::string>& roles);

    std::uint64_t send(const std::string& role, protocol::MessageType type, protocol::Body body = protocol::Empty{});
    // Waits for the reply to `seq`, which the hub has already checked is of the request's reply type; an
    // ERROR reply becomes a ParticipantFailure with its code. `roundtrip_s`: from the send to the reply's
    // arrival, which may be well before this call when another participant's reply was awaited first.
    protocol::Message await_reply(const std::string& role, std::uint64_t seq, double* roundtrip_s = nullptr);
    protocol::Message request(const std::string& role, protocol::MessageType type, protocol::Body body = protocol::Empty{}) {
        return await_reply(role, send(role, type, std::move(body)));
    }

    // BYE to every welcomed participant; waits up to `timeout_s` for the ACKs. Never throws.
    void goodbye(double timeout_s);

    const std::map<std::string, PeerInfo>& peers() const { return peers_; }
    double messaging_seconds() const { return messaging_s_; }  // time spent encoding/decoding/sending

private:
    // Waits up to wait_ms for messages, takes all there are, then checks every participant's liveness.
    // `interruptible`: a pending Ctrl-C throws Interrupted (not while saying goodbye).
    void pump(int wait_ms, bool interruptible = true);
    void wait_for_input(int wait_ms, bool interruptible);  // up to wait_ms, until a message is there
    void receive_all();
    void handle_stranger(const std::string& identity, const zmq::message_t& payload, bool multipart);
    void file_reply(const std::string& role, protocol::Message m);
    void check_liveness();
    [[noreturn]] void report_exit(const std::string& role, const std::string& how);
    // `droppable`: a heartbeat or a refusal to a stranger, dropped when the peer's queue is full (it does
    // not read); any other message to a peer that does not take it within run.timeout_s names it as hung.
    void send_raw(const std::string& identity, const protocol::Message& m, bool droppable = false);
    const std::string& identity_of(const std::string& role) const;

    zmq::context_t ctx_;
    zmq::socket_t socket_;
    std::string endpoint_, token_;
    HubTiming timing_;
    Launcher* launcher_;
    Log log_;
    std::map<std::string, PeerInfo> peers_;              // by role
    std::map<std::string, std::string> identity_role_;   // routing identity -> role
    std::map<std::string, std::string> role_identity_;
    struct Reply {
        protocol::Message message;
        double roundtrip_s;  // from the request's send to the reply's arrival
    };
    std::map<std::string, std::map<std::uint64_t, Reply>> inbox_;  // role -> seq -> reply
    struct OpenRequest {
        protocol::MessageType type;
        std::chrono::steady_clock::time_point sent;
    };
    std::map<std::string, std::map<std::uint64_t, OpenRequest>> open_;  // role -> seq -> unanswered request
    std::vector<std::string> expected_;
    std::uint64_t seq_ = 0, beat_seq_ = 0;  // requests, heartbeats
    std::chrono::steady_clock::time_point last_beat_sent_;
    double messaging_s_ = 0.0;
    bool closing_ = false;  // goodbye() has begun
    std::set<std::string> quiet_strangers_;  // unknown connections whose unanswered messages were logged once
    bool stray_heartbeats_ = false;          // an unknown connection sent HEARTBEAT with this run's token
};

}  // namespace sphfsi::coordinator
