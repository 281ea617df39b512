#include "sphfsi/coordinator/cli.hpp"

int main(int argc, char** argv) { return sphfsi::coordinator::main_cli(argc, argv); }
