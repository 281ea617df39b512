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
    Series(hid_t parent, const std::string& path, std::vector<hsize_t> row_shape, bool is_int, hsize_t rows_per_chunk);
    Series(hid_t parent, const std::string& path);  // opens an existing one
    void append(const void* rows, hsize_t count);   // `count` rows, row-major
    void truncate(hsize_t rows);                    // drop rows beyond `rows` (resume)
    hsize_t rows() const { return rows_; }
    const std::vector<hsize_t>& row_shape() const { return row_shape_; }
    bool is_int() const { return is_int_; }

private:
    Handle ds_;
    std::vector<hsize_t> row_shape_;
    hsize_t rows_ = 0;
    bool is_int_ = false;
};

Handle create_file(const std::string& path);
Handle open_file_rw(const std::string& path);
void write_string(hid_t parent, const std::string& name, const std::string& text);  // scalar UTF-8 dataset
void set_attribute(hid_t object, const std::string& name, const std::string& value);
void set_attribute(hid_t object, const std::string& name, double value);
bool exists(hid_t parent, const std::string& path);

}  // namespace sphfsi::coordinator::h5
