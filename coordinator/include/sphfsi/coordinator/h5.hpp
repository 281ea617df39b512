#pragma once
// Thin RAII over the HDF5 C API: only what the recorder needs (extendible, chunked, compressed
// datasets that grow along their first axis; string datasets and attributes).
#include <hdf5.h>

#include <cstdint>
#include <string>
#include <vector>

namespace sphfsi::coordinator::h5 {

class Handle {
public:
    Handle() = default;
    Handle(hid_t id, herr_t (*close)(hid_t), const std::string& what);
    Handle(Handle&& o) noexcept : id_(o.id_), close_(o.close_) { o.id_ = -1; }
    Handle& operator=(Handle&& o) noexcept;
    Handle(const Handle&) = delete;
    Handle& operator=(const Handle&) = delete;
    ~Handle() { reset(); }
    void reset();
    hid_t get() const { return id_; }
    explicit operator bool() const { return id_ >= 0; }

private:
    hid_t id_ = -1;
    herr_t (*close_)(hid_t) = nullptr;
};

// A dataset of rows of fixed `row_shape`, growing along axis 0. T is double or int32.
class Series {
public:
    Series() = default;
    // `compress`: only for datasets whose chunks are written once (one frame per chunk). A compressed
    // chunk that is rewritten moves in the file, and a kill between the move and the next flush would
    // leave the index pointing at reused space; uncompressed chunks are rewritten in place.
    Series(hid_t parent, const std::string& path, std::vector<hsize_t> row_shape, bool is_int, hsize_t rows_per_chunk,
           bool compress);
    Series(hid_t parent, const std::string& path);  // opens an existing one
    void append(const void* rows, hsize_t count);   // `count` rows, row-major
    void read(void* rows, hsize_t count, hsize_t first = 0) const;  // `count` rows from row `first`, row-major
    std::size_t row_bytes() const;
    hsize_t rows() const { return rows_; }
    const std::vector<hsize_t>& row_shape() const { return row_shape_; }
    bool is_int() const { return is_int_; }

private:
    Handle ds_;
    std::string path_;  // for messages
    std::vector<hsize_t> row_shape_;
    hsize_t rows_ = 0;
    bool is_int_ = false;
};

// A new file whose every flush can be interrupted: killed at any moment, the writer leaves a file that reads
// back with its last flush whole and, of the flush under way, at most some new rows (ordered_file.hpp).
// `chunk_index_k`: half the entries of a chunk index node, 0 for HDF5's 32 (tests use 2, to reach deep
// indexes in a few frames).
Handle create_file(const std::string& path, unsigned chunk_index_k = 0);
void flush(hid_t file);  // throws if HDF5 cannot write everything held (a full disk)
void write_string(hid_t parent, const std::string& name, const std::string& text);  // scalar UTF-8 dataset
void set_attribute(hid_t object, const std::string& name, const std::string& value);
void set_attribute(hid_t object, const std::string& name, double value);
void set_attribute(hid_t object, const std::string& name, std::int64_t value);
// A variable-length string attribute as set_attribute writes it; empty when absent or of another type.
std::string string_attribute(hid_t object, const std::string& name);
// The group `path` and the groups above it that are missing, each with room for a run's link names.
void create_groups(hid_t parent, const std::string& path);
bool exists(hid_t parent, const std::string& path);
// Names of the links in `group` ("/frames" -> {"fluid", "structure"}); empty if it does not exist.
std::vector<std::string> children(hid_t file, const std::string& group);
// Copies the object at `path` (a group with everything below it, or a dataset) between files.
void copy_object(hid_t source, hid_t target, const std::string& path);
// Copies the root group's attributes between files.
void copy_root_attributes(hid_t source, hid_t target);

}  // namespace sphfsi::coordinator::h5
