#include "sphfsi/protocol/participant.hpp"

#include <unistd.h>

#include <algorithm>
#include <atomic>
#include <chrono>
#include <cmath>
#include <condition_variable>
#include <csignal>
#include <cstdlib>
#include <deque>
#include <iostream>
#include <mutex>
#include <thread>
#include <zmq.hpp>

#include "sphfsi/protocol/codec.hpp"

namespace sphfsi::protocol {
namespace {
using Clock = std::chrono::steady_clock;

struct Options {
    std::string endpoint, token, name;
    double startup_timeout_s = 10.0;
};

// Wait policy after each reply. A coupled run exchanges a request per coupling window; with one window
// per fluid step that is hundreds per second, and on a VM every wake-up of a sleeping process costs tens
// of microseconds (docs/benchmarks.md, "Messaging"). So after replying a participant keeps polling its
// socket for up to 1 ms (yielding the core between polls) before it sleeps: the next request of a tight
// loop is taken at once, and the cores stay awake for the coordinator's wake-ups too. Measured on the
// elastic gate on a quiet machine (docs/benchmarks.md, "Coupled run"): messaging 9.5 % -> 4.6 % of the wall
// time with thesis windows, the coordinator's CPU 5.2 % -> 3.0 %; under load no measurable difference.
// SPHFSI_WAIT_SPIN_US sets the time (0: sleep at once).
std::chrono::microseconds wait_spin() {
    long us = 1000;
    if (const char* env = std::getenv("SPHFSI_WAIT_SPIN_US")) us = std::strtol(env, nullptr, 10);
    return std::chrono::microseconds(std::max(0L, std::min(us, 100000L)));
}

volatile std::sig_atomic_t g_stop = 0;
void on_signal(int) { g_stop = 1; }

void usage(const std::string& prog, const std::string& kind) {
    std::cerr << "usage: " << prog << " --connect tcp://HOST:PORT --name NAME [--token TOKEN] [--startup-timeout S]\n"
              << "       " << prog << " --schema    (print the [" << kind << "] scene keys as markdown)\n"
              << "A " << kind << " participant of sphfsi; normally started by the coordinator `sphfsi`.\n"
              << "The token may also come from the environment variable SPHFSI_TOKEN.\n";
}

// One DEALER socket shared by the main thread and the heartbeat thread. ZeroMQ sockets are not
// thread-safe, but may be used from several threads with a full memory barrier between uses: the
// mutex gives that. The main thread never holds it for longer than one short poll.
//
// While the main thread computes a request (`computing_`) nobody else reads the socket, so the heartbeat
// thread takes what arrives (take_while_computing): the coordinator's HEARTBEATs then count as signs of
// life during a long ADVANCE. A HEARTBEAT is dropped there (the main loop ignores them too); anything else
// is kept in `pending_`, in arrival order, and the main thread reads `pending_` before the socket.
// `computing_` is changed, and `pending_` filled and emptied, under the same mutex as every socket use: a
// message is either taken by the heartbeat thread before the main thread clears `computing_` (and then
// waits in `pending_`, ahead of anything still in the socket) or read from the socket by the main thread
// afterwards. None is lost or reordered.
class Link {
public:
    Link(zmq::context_t& ctx, const std::string& endpoint) : socket_(ctx, zmq::socket_type::dealer) {
        socket_.set(zmq::sockopt::linger, 0);
        socket_.set(zmq::sockopt::maxmsgsize, static_cast<int64_t>(DecodeLimits{}.max_bytes));
        socket_.connect(endpoint);
    }
    // Waits for room in ZeroMQ's queue in polls of 10 ms, the mutex released between them, and returns false,
    // unsent, once `give_up()` says so. A send that blocked held the mutex for as long as the queue was full:
    // with the coordinator gone and the queue filled by HEARTBEATs, for ever, and the heartbeat thread, which
    // ends a participant whose coordinator fell silent, waited on the mutex (a review, 2026-11-28).
    template <class GiveUp>
    bool send(const Message& m, GiveUp give_up) {
        std::string bytes = encode(m);
        while (true) {
            try {
                std::lock_guard lock(mutex_);
                zmq::pollitem_t item{socket_.handle(), 0, ZMQ_POLLOUT, 0};
                if (zmq::poll(&item, 1, std::chrono::milliseconds(10)) > 0 &&
                    socket_.send(zmq::buffer(bytes), zmq::send_flags::dontwait))
                    return true;
            } catch (const zmq::error_t& e) {
                if (e.num() != EINTR) throw;  // a signal: give_up decides
            }
            if (give_up()) return false;
        }
    }
    // Without blocking: when ZeroMQ's queue is full the coordinator is not reading anyway, and a heartbeat
    // thread blocked in send, holding the mutex, could no longer notice a signal or a silent coordinator.
    void send_heartbeat(const Message& m) {
        std::string bytes = encode(m);
        std::lock_guard lock(mutex_);
        (void)socket_.send(zmq::buffer(bytes), zmq::send_flags::dontwait);
    }
    // Main thread. Returns a message kept by the heartbeat thread if there is one; otherwise checks the
    // socket for up to `spin` (polling without sleeping, yielding the core between polls), then waits up
    // to `ms` asleep; returns false on timeout. See `wait_spin` above for why.
    bool receive(zmq::message_t& out, int ms, std::chrono::microseconds spin = {}) {
        try {
            {
                std::lock_guard lock(mutex_);
                if (!pending_.empty()) {
                    out = std::move(pending_.front());
                    pending_.pop_front();
                    return true;
                }
            }
            for (const auto until = Clock::now() + spin; spin.count() > 0 && Clock::now() < until;) {
                {
                    std::lock_guard lock(mutex_);
                    if (socket_.recv(out, zmq::recv_flags::dontwait)) return heard();
                }
                std::this_thread::yield();
            }
            std::lock_guard lock(mutex_);
            zmq::pollitem_t item{socket_.handle(), 0, ZMQ_POLLIN, 0};
            if (zmq::poll(&item, 1, std::chrono::milliseconds(ms)) <= 0) return false;
            return socket_.recv(out, zmq::recv_flags::dontwait) && heard();
        } catch (const zmq::error_t& e) {
            if (e.num() == EINTR) return false;  // a signal: the caller checks whether to stop
            throw;
        }
    }
    // Main thread: set while it handles a request, from taking it to having sent the reply.
    void set_computing(bool on) {
        std::lock_guard lock(mutex_);
        computing_ = on;
    }
    bool computing() const { return computing_.load(); }
    // Heartbeat thread: while the main thread computes, takes every message that has arrived (see above).
    void take_while_computing() {
        std::lock_guard lock(mutex_);
        try {
            zmq::message_t m;
            while (computing_ && socket_.recv(m, zmq::recv_flags::dontwait)) {
                heard();
                if (!is_heartbeat(m)) pending_.push_back(std::move(m));
            }
        } catch (const zmq::error_t& e) {
            if (e.num() != EINTR) throw;
        }
    }
    // Seconds since a message last arrived, taken by either thread.
    double silent_s() const {
        return std::chrono::duration<double>(Clock::now().time_since_epoch() - Clock::duration(last_heard_.load()))
            .count();
    }

private:
    bool heard() {
        last_heard_ = Clock::now().time_since_epoch().count();
        return true;
    }
    static bool is_heartbeat(const zmq::message_t& m) {
        try {
            return decode(m.data(), m.size()).type == MessageType::Heartbeat;
        } catch (const std::exception&) {
            return false;  // malformed: the main thread answers or logs it
        }
    }

    zmq::socket_t socket_;
    std::mutex mutex_;
    std::deque<zmq::message_t> pending_;
    std::atomic<bool> computing_{false};
    std::atomic<Clock::rep> last_heard_{Clock::now().time_since_epoch().count()};
};

class Runtime {
public:
    Runtime(Options opt, std::unique_ptr<Solver> solver) : opt_(std::move(opt)), solver_(std::move(solver)) {}

    int run() {
        zmq::context_t ctx(1);
        Link link(ctx, opt_.endpoint);
        link_ = &link;
        if (!handshake()) return g_stop ? 130 : 3;  // a signal while waiting is a stop, not a refusal
        std::thread beat([this] { heartbeat_loop(); });
        auto stop_beat = [&] {
            {
                std::lock_guard lock(beat_mutex_);
                stopping_ = true;
            }
            beat_cv_.notify_all();
            beat.join();
        };
        int code = 0;
        try {
            code = serve();
        } catch (const Unsent&) {
            // The statuses the main loop returns for the same reasons (docs/protocol.md, BYE).
            code = g_stop ? 130 : 4;
            log(g_stop ? std::string("stopped by signal with a reply waiting to go out")
                       : "the coordinator has been silent for " + std::to_string(link_->silent_s()) +
                             " s with a reply waiting to go out; exiting");
        } catch (...) {
            stop_beat();  // a joinable std::thread must not be destroyed
            throw;
        }
        stop_beat();
        return code;
    }

private:
    void log(const std::string& what) const { std::cerr << "[" << opt_.name << "] " << what << std::endl; }

    // Thrown when a reply cannot leave and the coordinator is silent past timeout_s, or a signal came.
    struct Unsent {};
    void reply(std::uint64_t seq, MessageType type, Body body = Empty{}) {
        Message m = make_message(type, seq, opt_.token, std::move(body));
        m.version = version_;
        if (!link_->send(m, [this] { return g_stop || link_->silent_s() > timeout_s_; })) throw Unsent{};
    }
    void reply_error(std::uint64_t seq, const std::string& code, const std::string& message) {
        reply(seq, MessageType::Error, ErrorReply{code, message, seq});
    }

    bool handshake() {
        Hello h{opt_.name, solver_->kind(), kOldestSupportedVersion, kProtocolVersion,
                "sphfsi-" + solver_->kind() + " " + SPHFSI_VERSION, ::getpid()};  // the log adds the protocol version
        Message hello = make_message(MessageType::Hello, 1, opt_.token, h);
        hello.version = kProtocolVersion;
        auto deadline = Clock::now() + std::chrono::duration<double>(opt_.startup_timeout_s);
        if (!link_->send(hello, [&] { return g_stop || Clock::now() >= deadline; })) {
            if (g_stop) log("stopped by signal before HELLO could be sent");
            else log("HELLO could not be sent to " + opt_.endpoint + " within " + std::to_string(opt_.startup_timeout_s) + " s");
            return false;
        }
        zmq::message_t raw;
        while (Clock::now() < deadline && !g_stop) {
            if (!link_->receive(raw, 100)) continue;
            Message m;
            try {
                m = decode(raw.data(), raw.size());
            } catch (const ProtocolError& e) {
                log(std::string("refused a malformed answer to HELLO: ") + e.what());
                continue;
            }
            if (m.type == MessageType::Error) {
                const auto& e = m.as<ErrorReply>();
                log("the coordinator refused us (" + e.code + "): " + e.message);
                return false;
            }
            if (m.type != MessageType::Welcome) continue;
            const auto& w = m.as<Welcome>();
            if (w.version < kOldestSupportedVersion || w.version > kProtocolVersion) {
                log("the coordinator chose protocol " + std::to_string(w.version) + ", outside the " +
                    std::to_string(kOldestSupportedVersion) + ".." + std::to_string(kProtocolVersion) + " we offered");
                return false;
            }
            version_ = w.version;
            heartbeat_s_ = w.heartbeat_s;
            timeout_s_ = w.timeout_s;
            return true;
        }
        if (g_stop) log("stopped by signal before WELCOME");
        else log("no WELCOME from " + opt_.endpoint + " within " + std::to_string(opt_.startup_timeout_s) + " s");
        return false;
    }

    // Sends HEARTBEAT every heartbeat_s. While the main thread computes, it is the only thread that can
    // see what the main loop checks between messages (a request can run for minutes: an ADVANCE of
    // millions of sub-steps), so it also
    //  - takes arriving messages (Link::take_while_computing), which keeps "last heard" current;
    //  - ends the process with status 130 once SIGTERM/SIGINT has set g_stop: the launcher's parent-death
    //    signal when the coordinator dies, or a user's kill, must not wait for the request to finish;
    //  - ends it with status 4 when the coordinator has been silent for more than timeout_s: one started
    //    by hand (--connect) gets no parent-death signal, and its coordinator may vanish mid-request.
    // The solver cannot be interrupted, and the reply would have nobody to go to, so it calls std::_Exit
    // after a log line: no destructor runs under the main thread's feet. The statuses are those the main
    // loop returns for the same reasons (docs/protocol.md, BYE); between requests it leaves both checks to
    // the main loop, which returns normally. It wakes at least every 0.1 s, so that a signal is acted on
    // within 0.1 s whatever heartbeat_s.
    void heartbeat_loop() {
        double tick_s = heartbeat_s_;
        if (!(tick_s >= 0.001)) tick_s = 0.001;  // also a NaN
        tick_s = std::min(tick_s, 0.1);
        const auto period = std::chrono::duration<double>(heartbeat_s_);
        std::unique_lock lock(beat_mutex_);
        std::uint64_t seq = 0;
        auto next_beat = Clock::now() + std::chrono::duration_cast<Clock::duration>(period);
        while (!stopping_) {
            // Wake for the next beat on time (never later than heartbeat_s after the last), and every tick_s.
            const auto wake = std::min(Clock::now() + std::chrono::duration_cast<Clock::duration>(std::chrono::duration<double>(tick_s)), next_beat);
            beat_cv_.wait_until(lock, wake, [this] { return stopping_; });
            if (stopping_) break;
            if (link_->computing()) {
                link_->take_while_computing();
                if (g_stop) quit(130, "stopped by signal in the middle of a request; exiting at once");
                if (const double silent = link_->silent_s(); silent > timeout_s_)
                    quit(4, "the coordinator has been silent for " + std::to_string(silent) +
                                " s while we computed; exiting at once");
            }
            if (Clock::now() < next_beat) continue;
            next_beat += std::chrono::duration_cast<Clock::duration>(period);
            if (next_beat < Clock::now()) next_beat = Clock::now();  // fell behind (a stalled machine): no burst
            Message m = make_message(MessageType::Heartbeat, ++seq, opt_.token, Heartbeat{progress_.steps.load()});
            m.version = version_;
            link_->send_heartbeat(m);
        }
    }

    [[noreturn]] void quit(int status, const std::string& why) const {
        log(why);
        std::_Exit(status);
    }

    int serve() {
        const auto spin = wait_spin();
        bool just_replied = false;  // spin only in the first wait after a request was answered
        zmq::message_t raw;
        while (true) {
            if (g_stop) {
                log("stopped by signal");
                return 130;
            }
            const bool got = link_->receive(raw, 100, just_replied ? spin : std::chrono::microseconds{});
            just_replied = false;
            if (!got) {
                const double silent = link_->silent_s();
                if (silent > timeout_s_) {
                    log("the coordinator has been silent for " + std::to_string(silent) + " s; exiting");
                    return 4;
                }
                continue;
            }
            Message m;
            try {
                m = decode(raw.data(), raw.size());
            } catch (const ProtocolError& e) {
                log(std::string("refused a malformed message: ") + e.what());
                if (e.answerable()) reply_error(e.seq(), e.code(), e.what());
                continue;
            }
            if (!is_answered(m.type)) {  // HEARTBEAT or ERROR, whatever its token
                if (m.type == MessageType::Error) {
                    const auto& e = m.as<ErrorReply>();
                    log("the coordinator sent ERROR " + e.code + ": " + e.message);
                }
                continue;
            }
            if (m.token != opt_.token) {
                reply_error(m.seq, "bad_token", "message carries a token that is not this run's");
                continue;
            }
            if (m.version != version_) {  // docs/protocol.md §3.1: every message after WELCOME is in the agreed one
                reply_error(m.seq, "version_mismatch", "message is in protocol " + std::to_string(m.version) +
                                                           "; this run agreed on " + std::to_string(version_));
                continue;
            }
            if (m.type == MessageType::Bye) {
                reply(m.seq, MessageType::Ack);
                return 0;
            }
            link_->set_computing(true);  // from here to the reply the heartbeat thread watches (heartbeat_loop)
            handle(m);
            link_->set_computing(false);
            just_replied = true;
        }
    }

    void handle(const Message& m) {
        try {
            if (m.type != MessageType::Init && !initialised_)
                return reply_error(m.seq, "bad_state", std::string(to_string(m.type)) + " before INIT");
            if (inside_failed_window_ && m.type != MessageType::Restore)
                return reply_error(m.seq, "bad_state", std::string(to_string(m.type)) + " after a failed ADVANCE: the state is "
                                                       "somewhere inside that window, at no window end (RESTORE returns to the saved one)");
            switch (m.type) {
                case MessageType::Init: {
                    // READY is for good (docs/protocol.md §3): a second INIT would silently rebuild the solver
                    // under a coordinator that is mid-run. A failed INIT leaves us WELCOMED, free to retry.
                    if (initialised_) return reply_error(m.seq, "bad_state", "INIT after a successful INIT");
                    InitRequest req = m.as<InitRequest>();
                    // t0 becomes the solver's clock: from a NaN or infinite start every ADVANCE would fail
                    // check_window, leaving a participant that answers but can never advance.
                    if (!std::isfinite(req.t0))
                        throw CodedError("bad_message", "INIT t0 = " + seconds(req.t0) + " is not a finite time");
                    schema::Errors errors;
                    req.config = solver_->schema().validate(req.config, solver_->kind(), errors);
                    schema::throw_if_any(errors, "INIT config");
                    InitReply r = solver_->init(req);
                    initialised_ = true;
                    last_t_ = saved_t_ = req.t0;
                    return reply(m.seq, MessageType::Ready, std::move(r));
                }
                case MessageType::Advance: {
                    const AdvanceRequest& req = m.as<AdvanceRequest>();
                    check_inputs(req.inputs);
                    auto start = Clock::now();
                    AdvanceReply r;
                    try {
                        r = solver_->advance(req, progress_);
                    } catch (const CodedError& e) {
                        // bad_message and bad_state refuse a request that was not carried out (docs/protocol.md §3).
                        inside_failed_window_ = e.code() != "bad_message" && e.code() != "bad_state";
                        throw;
                    } catch (...) {
                        inside_failed_window_ = true;
                        throw;
                    }
                    r.compute_s = std::chrono::duration<double>(Clock::now() - start).count();
                    last_t_ = r.t;
                    return reply(m.seq, MessageType::Advanced, std::move(r));
                }
                case MessageType::Save:
                    solver_->save();
                    saved_t_ = last_t_;
                    return reply(m.seq, MessageType::Ack);
                case MessageType::Restore:
                    solver_->restore();
                    last_t_ = saved_t_;
                    inside_failed_window_ = false;
                    return reply(m.seq, MessageType::Ack);
                case MessageType::Snapshot: return reply(m.seq, MessageType::Frame, Frame{last_t_, solver_->snapshot()});
                case MessageType::Checkpoint: return reply(m.seq, MessageType::State, State{last_t_, solver_->checkpoint()});
                default:
                    return reply_error(m.seq, "bad_state", std::string(to_string(m.type)) + " is not a request a participant answers");
            }
        } catch (const CodedError& e) {  // solver failures and protocol violations carry their own code
            log(e.code() + ": " + e.what());
            reply_error(m.seq, e.code(), e.what());
        } catch (const ConfigError& e) {
            log(std::string("bad_config: ") + e.what());
            reply_error(m.seq, "bad_config", e.what());
        } catch (const std::exception& e) {
            log(std::string("internal error: ") + e.what());
            reply_error(m.seq, "internal", e.what());
        }
    }

    // The coordinator always sends exactly the inputs of the solver's kind (docs/protocol.md, ADVANCE): a
    // missing one would leave the solver on stale or zero values, an extra one would be ignored, and either
    // means the two sides disagree about the run. The solver says which it takes, as INIT set it up.
    void check_inputs(const Fields& inputs) const {
        const auto expected = solver_->advance_inputs();
        if (!expected) return;
        std::string takes;
        for (const auto& name : *expected) takes += (takes.empty() ? "" : ", ") + name;
        takes = " (this " + solver_->kind() + (takes.empty() ? " takes none)" : " takes exactly: " + takes + ")");
        for (const auto& name : *expected)
            if (!inputs.count(name))
                throw CodedError("bad_message", solver_->kind() + ": ADVANCE inputs lack the field '" + name + "'" + takes);
        for (const auto& [name, field] : inputs)
            if (std::find(expected->begin(), expected->end(), name) == expected->end())
                throw CodedError("bad_message", solver_->kind() + ": ADVANCE inputs have the unknown field '" +
                                                    printable(name) + "'" + takes);
    }

    Options opt_;
    std::unique_ptr<Solver> solver_;
    Link* link_ = nullptr;
    Progress progress_;
    std::uint32_t version_ = kProtocolVersion;
    double heartbeat_s_ = 0.5, timeout_s_ = 5.0;
    double last_t_ = 0.0, saved_t_ = 0.0;  // time of the current and of the saved state
    // An ADVANCE failed part-way (diverged, not_converged, internal): the solver's state lies inside that
    // window, where no FRAME, STATE or SAVE may claim a window end's time.
    bool inside_failed_window_ = false;
    bool initialised_ = false;
    std::mutex beat_mutex_;
    std::condition_variable beat_cv_;
    bool stopping_ = false;
};
}  // namespace

int run_participant(int argc, char** argv, std::unique_ptr<Solver> solver) {
    Options opt;
    if (const char* t = std::getenv("SPHFSI_TOKEN")) opt.token = t;
    const std::string prog = argc > 0 ? argv[0] : "participant";
    for (int i = 1; i < argc; ++i) {
        std::string a = argv[i];
        auto next = [&]() -> std::string {
            if (i + 1 >= argc) throw std::invalid_argument(a + " needs a value");
            return argv[++i];
        };
        try {
            if (a == "--connect") opt.endpoint = next();
            else if (a == "--token") opt.token = next();
            else if (a == "--name") opt.name = next();
            else if (a == "--startup-timeout") opt.startup_timeout_s = std::stod(next());
            else if (a == "--schema") {
                std::cout << solver->schema().document(solver->kind());
                return 0;
            } else if (a == "--help" || a == "-h") {
                usage(prog, solver->kind());
                return 0;
            } else {
                std::cerr << prog << ": unknown argument '" << a << "'\n";
                usage(prog, solver->kind());
                return 2;
            }
        } catch (const std::exception& e) {
            std::cerr << prog << ": " << e.what() << "\n";
            return 2;
        }
    }
    if (opt.endpoint.empty() || opt.token.empty()) {
        usage(prog, solver->kind());
        return 2;
    }
    if (opt.name.empty()) opt.name = solver->kind();
    std::signal(SIGTERM, on_signal);
    std::signal(SIGINT, on_signal);
    try {
        return Runtime(std::move(opt), std::move(solver)).run();
    } catch (const std::exception& e) {
        std::cerr << prog << ": fatal: " << e.what() << "\n";
        return 1;
    }
}

}  // namespace sphfsi::protocol
