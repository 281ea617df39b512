#pragma once
// Starts participant programs as child processes and makes sure none outlives the coordinator.
#include <sys/types.h>

#include <map>
#include <optional>
#include <string>
#include <vector>

namespace sphfsi::coordinator {

class Launcher {
public:
    Launcher() = default;
    Launcher(const Launcher&) = delete;
    Launcher& operator=(const Launcher&) = delete;
    ~Launcher();  // stops whatever is still running

    // Starts `argv` as `role`; the token goes in the environment (SPHFSI_TOKEN), not on the command line.
    void start(const std::string& role, const std::vector<std::string>& argv, const std::string& token);

    // Non-blocking: a role whose process has exited since the last call, with a description of how.
    std::optional<std::pair<std::string, std::string>> poll_exited();

    // Waits up to `grace_s` for each child to exit by itself, then SIGTERM, then SIGKILL. Reaps all. Returns
    // a line for each child that did not end cleanly (a non-zero status, a signal, or our SIGTERM/SIGKILL):
    // after BYE and ACK a participant exits 0, so anything else is worth a line in the log.
    std::vector<std::string> stop_all(double grace_s);

    bool running(const std::string& role) const;

private:
    std::map<std::string, pid_t> children_;
};

// The directory of the running coordinator binary: built-in participants live beside it.
std::string own_directory();
// Human words for a wait() status: "exited with status 3", "killed by signal 9 (Killed)".
std::string describe_exit(int status);

}  // namespace sphfsi::coordinator
