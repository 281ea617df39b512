// sphfsi-structure: the FEM beam participant. All the work is in the library; see participant.hpp.
#include <memory>

#include "sphfsi/protocol/participant.hpp"
#include "sphfsi/structure/heap.hpp"
#include "sphfsi/structure/participant.hpp"

int main(int argc, char** argv) {
    sphfsi::structure::keep_freed_memory();
    return sphfsi::protocol::run_participant(argc, argv, std::make_unique<sphfsi::structure::StructureSolver>());
}
