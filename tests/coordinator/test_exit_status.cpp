// describe_exit: how the coordinator names the way a participant ended. The statuses of the reference runtime
// (docs/protocol.md, BYE) say why it left; a status 4 read as a plain exit blamed the participant for a
// coordinator that had been stopped (SIGSTOP) past timeout_s (a kill probe, 2026-11-28).
#include <doctest/doctest.h>

#include <cstdlib>
#include <string>

#include "sphfsi/coordinator/launcher.hpp"

using sphfsi::coordinator::describe_exit;

namespace {
// A real wait status: the shell's (std::system returns what waitpid gave).
int status_of(const char* command) { return std::system(command); }
}  // namespace

TEST_CASE("an exit status of the reference runtime is named with its meaning") {
    const std::string silent = describe_exit(status_of("exit 4"));
    CHECK(silent.rfind("exited with status 4", 0) == 0);
    CHECK(silent.find("heard nothing from the coordinator") != std::string::npos);
    CHECK(describe_exit(status_of("exit 3")).find("refused, or no WELCOME") != std::string::npos);
    CHECK(describe_exit(status_of("exit 130")).find("SIGTERM or SIGINT") != std::string::npos);
    CHECK(describe_exit(status_of("exit 7")) == "exited with status 7");
    CHECK(describe_exit(status_of("kill -9 $$")).rfind("was killed by signal 9", 0) == 0);
}
