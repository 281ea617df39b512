#pragma once
// An HDF5 file driver that makes every flush safe to interrupt: a record whose writer is killed at any
// moment reads back with the stock library (h5py, ParaView) without repair. See ordered_file.cpp.
#include <hdf5.h>

#include <string>

namespace sphfsi::coordinator::h5 {

// Selects the driver in a file access property list (it is registered with HDF5 on first use).
void use_ordered_file_driver(hid_t fapl);

// Why the first write through the driver that failed in this process did (empty if none did): "cannot
// grow the file: No space left on device". The file keeps the state of its last whole flush.
const std::string& ordered_file_failure();

}  // namespace sphfsi::coordinator::h5
