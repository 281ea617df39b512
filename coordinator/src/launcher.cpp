#include "sphfsi/coordinator/launcher.hpp"

#include <signal.h>
#include <sys/prctl.h>
#include <sys/wait.h>
#include <unistd.h>

#include <chrono>
#include <cstdio>
#include <cstring>
#include <filesystem>
#include <stdexcept>
#include <thread>

namespace sphfsi::coordinator {

std::string own_directory() {
    return std::filesystem::read_symlink("/proc/self/exe").parent_path().string();
}

// The reference runtime's statuses (docs/protocol.md, BYE) carry their reason along: a status 4 named as a
// bare exit blamed the participant for a coordinator stopped past timeout_s (a kill probe, 2026-11-28). A
// foreign participant may mean something else by them, hence "the reference runtime's".
std::string describe_exit(int status) {
    if (WIFEXITED(status)) {
        const int code = WEXITSTATUS(status);
        const char* meaning = code == 3   ? "refused, or no WELCOME"
                              : code == 4 ? "it heard nothing from the coordinator for run.timeout_s: was the "
                                            "coordinator stopped, or starved of CPU?"
                              : code == 130 ? "stopped by SIGTERM or SIGINT"
                                            : nullptr;
        return "exited with status " + std::to_string(code) +
               (meaning ? std::string(" (the reference runtime's status for: ") + meaning + ")" : "");
    }
    if (WIFSIGNALED(status))
        return "was killed by signal " + std::to_string(WTERMSIG(status)) + " (" + strsignal(WTERMSIG(status)) + ")";
    return "stopped (status " + std::to_string(status) + ")";
}

Launcher::~Launcher() { (void)stop_all(0.0); }

void Launcher::start(const std::string& role, const std::vector<std::string>& argv, const std::string& token) {
    if (argv.empty()) throw std::invalid_argument("no program for " + role);
    std::vector<char*> args;
    for (const auto& a : argv) args.push_back(const_cast<char*>(a.c_str()));
    args.push_back(nullptr);
    std::string env_token = "SPHFSI_TOKEN=" + token;
    pid_t parent = ::getpid();
    pid_t pid = ::fork();
    if (pid < 0) throw std::runtime_error("cannot start " + role + ": fork failed: " + std::strerror(errno));
    if (pid == 0) {
        // Die with the coordinator, even if it is killed with SIGKILL.
        ::prctl(PR_SET_PDEATHSIG, SIGTERM);
        if (::getppid() != parent) ::_exit(127);
        // Own process group: Ctrl-C reaches the coordinator only, which then shuts the run down in order.
        ::setpgid(0, 0);
        // Inherit no descriptor beyond stdio: an inherited record file keeps its HDF5 lock alive in a
        // participant for the moment it outlives a killed coordinator, and `--resume` right after found
        // the record locked. (close_range is a plain system call, safe between fork and exec.)
        if (::close_range(3, ~0U, 0) != 0)
            for (long fd = 3, n = ::sysconf(_SC_OPEN_MAX); fd < n; ++fd) ::close(static_cast<int>(fd));
        // The coordinator ignores SIGPIPE (a dead participant's socket is its to report), and an ignored
        // signal stays ignored across exec: a participant, or a wrapper script's pipeline, gets the default back.
        ::signal(SIGPIPE, SIG_DFL);
        ::putenv(env_token.data());
        ::execvp(args[0], args.data());
        std::fprintf(stderr, "[%s] cannot execute %s: %s\n", role.c_str(), args[0], std::strerror(errno));
        ::_exit(127);
    }
    children_[role] = pid;
}

namespace {
// Reaps `pid` if it has exited, after killing what is left of its process group: a participant started as a
// wrapper (a script that runs the solver as its child) leaves the solver behind when it dies or is stopped.
// Until the exited leader is reaped its pid, and so its group id, cannot be taken by another process.
bool reap_if_exited(pid_t pid, int& status) {
    siginfo_t info{};
    if (::waitid(P_PID, static_cast<id_t>(pid), &info, WEXITED | WNOHANG | WNOWAIT) != 0 || info.si_pid != pid) return false;
    ::kill(-pid, SIGKILL);
    return ::waitpid(pid, &status, 0) == pid;
}

// The child and its process group (the group may not exist yet if the child has not reached setpgid).
void signal_all_of(pid_t pid, int sig) {
    ::kill(-pid, sig);
    ::kill(pid, sig);
}
}  // namespace

std::optional<std::pair<std::string, std::string>> Launcher::poll_exited() {
    for (auto it = children_.begin(); it != children_.end(); ++it) {
        int status = 0;
        if (reap_if_exited(it->second, status)) {
            std::string role = it->first;
            children_.erase(it);
            return std::make_pair(role, describe_exit(status));
        }
    }
    return std::nullopt;
}

bool Launcher::running(const std::string& role) const { return children_.count(role) > 0; }

std::vector<std::string> Launcher::stop_all(double grace_s) {
    using namespace std::chrono;
    std::vector<std::string> notes;
    std::string stopped_by;  // empty while children may still exit by themselves
    auto wait_all = [&](double seconds) {
        auto until = steady_clock::now() + duration<double>(seconds);
        do {
            for (auto it = children_.begin(); it != children_.end();) {
                int status = 0;
                if (!reap_if_exited(it->second, status)) {
                    ++it;
                    continue;
                }
                if (!stopped_by.empty()) notes.push_back(it->first + " " + describe_exit(status) + " after " + stopped_by);
                else if (!(WIFEXITED(status) && WEXITSTATUS(status) == 0)) notes.push_back(it->first + " " + describe_exit(status));
                it = children_.erase(it);
            }
            if (children_.empty()) return;
            std::this_thread::sleep_for(milliseconds(10));
        } while (steady_clock::now() < until);
    };
    wait_all(grace_s);
    char grace[32];
    std::snprintf(grace, sizeof grace, "%.1f s", grace_s);
    stopped_by = std::string("SIGTERM (it had not exited ") + grace + " after the run ended)";
    for (auto& [role, pid] : children_) signal_all_of(pid, SIGTERM);
    wait_all(1.0);
    for (auto& [role, pid] : children_) {
        signal_all_of(pid, SIGCONT);  // a stopped (SIGSTOP) child cannot act on SIGTERM; SIGKILL works regardless
        signal_all_of(pid, SIGKILL);
        ::waitpid(pid, nullptr, 0);
        notes.push_back(role + " was killed with SIGKILL: it ignored SIGTERM for 1 s");
    }
    children_.clear();
    return notes;
}

}  // namespace sphfsi::coordinator
