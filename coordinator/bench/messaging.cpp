// Messaging cost on this machine: a bare ZeroMQ ROUTER/DEALER ping-pong between two processes,
// next to a full ADVANCE round trip through the coordinator's Hub to a participant process
// (encode, send, decode, dispatch to a solver that does no physics, and back), empty and with
// 1,000 interface vertices (force in, displacement and velocity out: 16 kB of float64 out and 32 kB
// back, 48 kB a round trip). Prints medians and 90th percentiles.
//
//   sphfsi-bench-messaging [repeats]
#include <algorithm>
#include <chrono>
#include <cstdio>
#include <cstring>
#include <string>
#include <vector>
#include <zmq.hpp>

#include "sphfsi/coordinator/hub.hpp"
#include "sphfsi/coordinator/launcher.hpp"
#include "sphfsi/coordinator/session.hpp"
#include "sphfsi/protocol/participant.hpp"

using namespace sphfsi;
using namespace sphfsi::protocol;
using Clock = std::chrono::steady_clock;

namespace {
// The benchmark's own participant: answers with outputs the size of its inputs and no physics, so
// what is timed is messaging alone.
class NoPhysics : public Solver {
public:
    std::string kind() const override { return "structure"; }
    const schema::TableSchema& schema() const override {
        static schema::TableSchema s("benchmark participant");
        return s;
    }
    InitReply init(const InitRequest& r) override {
        t_ = r.t0;
        return InitReply{1.0, InterfaceMesh{F64Array({4, 2}, {0, 0, 1, 0, 1, 1, 0, 1}), I32Array({1, 4}, {0, 1, 2, 3})}, {}, {}};
    }
    AdvanceReply advance(const AdvanceRequest& r, Progress& p) override {
        p.tick();
        t_ = r.t + r.dt;
        AdvanceReply out;
        out.t = t_;
        out.dt_wanted = 1.0;
        out.substeps = 1;
        if (auto it = r.inputs.find("force"); it != r.inputs.end()) {
            out.outputs["displacement"] = it->second;
            out.outputs["velocity"] = it->second;
        }
        return out;
    }
    void save() override {}
    void restore() override {}
    Fields snapshot() override { return {}; }
    std::vector<std::uint8_t> checkpoint() override { return {}; }

private:
    double t_ = 0;
};

double median(std::vector<double> v) {
    std::sort(v.begin(), v.end());
    const std::size_t n = v.size();
    return n % 2 ? v[n / 2] : 0.5 * (v[n / 2 - 1] + v[n / 2]);  // the default 2,000 repeats are an even count
}
double percentile(std::vector<double> v, double q) {
    std::sort(v.begin(), v.end());
    return v[static_cast<std::size_t>(q * (v.size() - 1))];
}

// The echo side of the bare ping-pong, in its own process (re-executed: no state shared with the parent).
int echo(const std::string& endpoint) {
    zmq::context_t c(1);
    zmq::socket_t dealer(c, zmq::socket_type::dealer);
    dealer.set(zmq::sockopt::linger, 0);
    dealer.set(zmq::sockopt::rcvtimeo, 10000);  // never hang: give up after 10 s of silence
    dealer.connect(endpoint);
    dealer.send(zmq::str_buffer("hello"));
    while (true) {
        zmq::message_t m;
        if (!dealer.recv(m)) return 0;
        if (m.size() == 3 && std::memcmp(m.data(), "end", 3) == 0) return 0;
        dealer.send(m, zmq::send_flags::none);
    }
}

void bare_pingpong(const std::string& self, int repeats, std::size_t bytes) {
    zmq::context_t ctx(1);
    zmq::socket_t router(ctx, zmq::socket_type::router);
    router.set(zmq::sockopt::linger, 0);
    router.set(zmq::sockopt::rcvtimeo, 10000);
    router.bind("tcp://127.0.0.1:*");
    std::string endpoint = router.get(zmq::sockopt::last_endpoint);
    coordinator::Launcher launcher;
    launcher.start("echo", {self, "--echo", endpoint}, "unused");
    zmq::message_t id, first;
    if (!router.recv(id) || !router.recv(first)) throw std::runtime_error("echo process did not connect");
    std::string payload(bytes, 'p');
    std::vector<double> us;
    for (int i = 0; i < repeats + 100; ++i) {
        auto t0 = Clock::now();
        router.send(zmq::buffer(id.data(), id.size()), zmq::send_flags::sndmore);
        router.send(zmq::buffer(payload), zmq::send_flags::none);
        zmq::message_t rid, reply;
        if (!router.recv(rid) || !router.recv(reply)) throw std::runtime_error("echo process went silent");
        if (i >= 100) us.push_back(std::chrono::duration<double, std::micro>(Clock::now() - t0).count());
    }
    router.send(zmq::buffer(id.data(), id.size()), zmq::send_flags::sndmore);
    router.send(zmq::str_buffer("end"), zmq::send_flags::none);
    launcher.stop_all(2.0);
    std::printf("%-44s %10.1f %10.1f\n", ("bare ZeroMQ ping-pong, " + std::to_string(bytes) + " B each way").c_str(),
                median(us), percentile(us, 0.9));
}

void advance_roundtrip(const std::string& self, int repeats) {
    coordinator::Launcher launcher;
    coordinator::Hub hub("tcp://127.0.0.1:*", "benchtoken0123456789abcdef012345", {0.5, 10.0, 10.0}, &launcher,
                         [](const std::string&) {});
    launcher.start("structure", {self, "--participant", "--connect", hub.endpoint(), "--name", "structure"}, hub.token());
    hub.await_hellos({"structure"});
    hub.request("structure", MessageType::Init, InitRequest{Value(Value::Table{}), 0.0, std::nullopt, {}, {}});
    coordinator::Session session(hub);
    for (std::size_t n : {std::size_t{0}, std::size_t{1000}}) {
        Fields inputs;
        if (n) inputs["force"] = F64Array::zeros(n, 2);
        std::vector<double> us;
        double t = 0;
        for (int i = 0; i < repeats + 100; ++i) {
            auto t0 = Clock::now();
            auto r = session.advance("structure", t, 1e-3, 1, 0, inputs);
            t = r.reply.t;
            if (i >= 100) us.push_back(std::chrono::duration<double, std::micro>(Clock::now() - t0).count());
        }
        std::printf("%-44s %10.1f %10.1f\n", ("ADVANCE through the coordinator, " + std::to_string(n) + " vertices").c_str(),
                    median(us), percentile(us, 0.9));
    }
    hub.goodbye(2.0);
    launcher.stop_all(2.0);
}
}  // namespace

int main(int argc, char** argv) {
    if (argc > 1 && std::strcmp(argv[1], "--participant") == 0) {
        // re-executed as the participant process: drop our own flag and run the standard runtime
        std::vector<char*> args{argv[0]};
        for (int i = 2; i < argc; ++i) args.push_back(argv[i]);
        return run_participant(static_cast<int>(args.size()), args.data(), std::make_unique<NoPhysics>());
    }
    if (argc > 2 && std::strcmp(argv[1], "--echo") == 0) return echo(argv[2]);
    const int repeats = argc > 1 ? std::atoi(argv[1]) : 2000;
    if (argc > 2 || repeats <= 0) {  // --help too: print the usage rather than run a benchmark nobody asked for
        const bool help = argc == 2 && (std::strcmp(argv[1], "--help") == 0 || std::strcmp(argv[1], "-h") == 0);
        std::fprintf(help ? stdout : stderr, "usage: %s [REPEATS > 0 (default 2000)]\n", argv[0]);
        return help ? 0 : 2;
    }
    std::printf("round trips between two processes on 127.0.0.1, %d repeats\n", repeats);
    std::printf("%-44s %10s %10s\n", "exchange", "median us", "p90 us");
    const std::string self = coordinator::own_directory() + "/sphfsi-bench-messaging";
    bare_pingpong(self, repeats, 1);
    // The bytes a 1,000-vertex ADVANCE moves per round trip (16 kB of force out, 32 kB of displacement and
    // velocity back), split evenly: the echo returns what it gets. Until 2026-11-28 this sent 48 kB each way.
    bare_pingpong(self, repeats, 24000);
    advance_roundtrip(self, repeats);
    return 0;
}
