#pragma once
namespace sphfsi::coordinator {
// The `sphfsi` command line; returns the exit status.
int main_cli(int argc, char** argv);
}  // namespace sphfsi::coordinator
