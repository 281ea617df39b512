#pragma once
// An HDF5 file driver that makes every flush safe to interrupt: a record whose writer is killed at any
// moment reads back with the stock library (h5py, ParaView) without repair. See ordered_file.cpp.
#include <hdf5.h>

namespace sphfsi::coordinator::h5 {

// Selects the driver in a file access property list (it is registered with HDF5 on first use).
void use_ordered_file_driver(hid_t fapl);

}  // namespace sphfsi::coordinator::h5
