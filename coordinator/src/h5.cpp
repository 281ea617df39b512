#include "sphfsi/coordinator/h5.hpp"

#include <exception>
#include <stdexcept>

#include "sphfsi/coordinator/ordered_file.hpp"

namespace sphfsi::coordinator::h5 {
namespace {
hid_t check(hid_t id, const std::string& what) {
    if (id < 0) throw std::runtime_error("HDF5: cannot " + what);
    return id;
}
void check(herr_t rc, const std::string& what, int) {
    if (rc < 0) throw std::runtime_error("HDF5: cannot " + what);
}
// Room for the link names a group gets over a run, so that its name heap never has to move: a moved heap
// is two pieces on disk (header and names), and a kill between their writes left the group unreadable
// (ordered_file.cpp). HDF5's own size holds about 5 names. The root group takes it from the file's
// creation properties.
constexpr std::size_t kNameHeapBytes = 1024;

std::string parent_of(const std::string& path) {  // "/frames/fluid/tag" -> "/frames/fluid"; "scene" -> ""
    const std::size_t slash = path.rfind('/');
    return slash == std::string::npos ? std::string() : path.substr(0, slash);
}
}  // namespace

Handle::Handle(hid_t id, herr_t (*close)(hid_t), const std::string& what) : id_(check(id, what)), close_(close) {}

Handle& Handle::operator=(Handle&& o) noexcept {
    if (this != &o) {
        reset();
        id_ = o.id_;
        close_ = o.close_;
        o.id_ = -1;
    }
    return *this;
}

void Handle::reset() {
    if (id_ >= 0 && close_) close_(id_);
    id_ = -1;
}

Series::Series(hid_t parent, const std::string& path, std::vector<hsize_t> row_shape, bool is_int, hsize_t rows_per_chunk,
               bool compress)
    : path_(path), row_shape_(std::move(row_shape)), is_int_(is_int) {
    std::vector<hsize_t> dims{0}, maxdims{H5S_UNLIMITED}, chunk{rows_per_chunk};
    for (hsize_t s : row_shape_) {
        dims.push_back(s);
        maxdims.push_back(s);
        chunk.push_back(s ? s : 1);
    }
    Handle space(H5Screate_simple(static_cast<int>(dims.size()), dims.data(), maxdims.data()), H5Sclose, "create space");
    Handle dcpl(H5Pcreate(H5P_DATASET_CREATE), H5Pclose, "create dataset properties");
    check(H5Pset_chunk(dcpl.get(), static_cast<int>(chunk.size()), chunk.data()), "chunk " + path, 0);
    if (compress) {
        check(H5Pset_shuffle(dcpl.get()), "shuffle " + path, 0);
        check(H5Pset_deflate(dcpl.get(), 1), "compress " + path, 0);  // cheap: frames are written while the run goes on
    }
    create_groups(parent, parent_of(path));
    ds_ = Handle(H5Dcreate2(parent, path.c_str(), is_int ? H5T_STD_I32LE : H5T_IEEE_F64LE, space.get(), H5P_DEFAULT,
                            dcpl.get(), H5P_DEFAULT),
                 H5Dclose, "create dataset " + path);
}

Series::Series(hid_t parent, const std::string& path) : path_(path) {
    ds_ = Handle(H5Dopen2(parent, path.c_str(), H5P_DEFAULT), H5Dclose, "open dataset " + path);
    Handle space(H5Dget_space(ds_.get()), H5Sclose, "get space");
    const int rank = H5Sget_simple_extent_ndims(space.get());
    if (rank < 1) throw std::runtime_error("HDF5: " + path + " is not a dataset of rows");
    std::vector<hsize_t> dims(static_cast<std::size_t>(rank));
    check(H5Sget_simple_extent_dims(space.get(), dims.data(), nullptr), "read the shape of " + path, 0);
    rows_ = dims[0];
    row_shape_.assign(dims.begin() + 1, dims.end());
    Handle type(H5Dget_type(ds_.get()), H5Tclose, "get type");
    is_int_ = H5Tget_class(type.get()) == H5T_INTEGER;
}

void Series::append(const void* rows, hsize_t count) {
    if (count == 0) return;
    std::vector<hsize_t> dims{rows_ + count}, start{rows_}, n{count};
    for (hsize_t s : row_shape_) {
        dims.push_back(s);
        start.push_back(0);
        n.push_back(s);
    }
    check(H5Dset_extent(ds_.get(), dims.data()), "extend " + path_, 0);
    Handle file_space(H5Dget_space(ds_.get()), H5Sclose, "get space");
    check(H5Sselect_hyperslab(file_space.get(), H5S_SELECT_SET, start.data(), nullptr, n.data(), nullptr),
          "select rows of " + path_, 0);
    Handle mem_space(H5Screate_simple(static_cast<int>(n.size()), n.data(), nullptr), H5Sclose, "create space");
    check(H5Dwrite(ds_.get(), is_int_ ? H5T_NATIVE_INT32 : H5T_NATIVE_DOUBLE, mem_space.get(), file_space.get(), H5P_DEFAULT, rows),
          "write rows of " + path_, 0);
    rows_ += count;
}

void Series::read(void* rows, hsize_t count, hsize_t first) const {
    if (count == 0) return;
    std::vector<hsize_t> start{first}, n{count};
    for (hsize_t d : row_shape_) {
        start.push_back(0);
        n.push_back(d);
    }
    Handle file_space(H5Dget_space(ds_.get()), H5Sclose, "get space");
    check(H5Sselect_hyperslab(file_space.get(), H5S_SELECT_SET, start.data(), nullptr, n.data(), nullptr),
          "select rows of " + path_, 0);
    Handle mem_space(H5Screate_simple(static_cast<int>(n.size()), n.data(), nullptr), H5Sclose, "create space");
    check(H5Dread(ds_.get(), is_int_ ? H5T_NATIVE_INT32 : H5T_NATIVE_DOUBLE, mem_space.get(), file_space.get(), H5P_DEFAULT, rows),
          "read rows of " + path_, 0);
}

std::size_t Series::row_bytes() const {
    std::size_t n = is_int_ ? sizeof(std::int32_t) : sizeof(double);
    for (hsize_t d : row_shape_) n *= d;
    return n;
}

Handle create_file(const std::string& path, unsigned chunk_index_k) {
    // Metadata reaches the disk only when we flush (after each frame), in an order that every kill leaves
    // readable (ordered_file.cpp). Evictions off: the cache serialises each entry once, at the flush.
    Handle fapl(H5Pcreate(H5P_FILE_ACCESS), H5Pclose, "create file access properties");
    H5AC_cache_config_t mdc;
    mdc.version = H5AC__CURR_CACHE_CONFIG_VERSION;
    check(H5Pget_mdc_config(fapl.get(), &mdc), "read the metadata cache settings", 0);
    mdc.evictions_enabled = false;
    mdc.incr_mode = H5C_incr__off;
    mdc.flash_incr_mode = H5C_flash_incr__off;
    mdc.decr_mode = H5C_decr__off;
    mdc.set_initial_size = true;
    mdc.initial_size = 16 * 1024 * 1024;
    mdc.max_size = 64 * 1024 * 1024;
    check(H5Pset_mdc_config(fapl.get(), &mdc), "set the metadata cache", 0);
    use_ordered_file_driver(fapl.get());  // every moment of a flush leaves a readable file (ordered_file.cpp)
    // No free-space manager: space HDF5 frees is not handed out again, as the file on disk may still refer
    // to it until the flush (a little space is lost when an attribute changes type). This takes a
    // version-2 superblock with a file-space message, which HDF5 1.10 and later read (1.8 may not).
    Handle fcpl(H5Pcreate(H5P_FILE_CREATE), H5Pclose, "create file creation properties");
    check(H5Pset_local_heap_size_hint(fcpl.get(), kNameHeapBytes), "size the root group's name heap", 0);
    check(H5Pset_file_space_strategy(fcpl.get(), H5F_FSPACE_STRATEGY_NONE, 0, 1), "set the file space strategy", 0);
    if (chunk_index_k) check(H5Pset_istore_k(fcpl.get(), chunk_index_k), "set the chunk index size", 0);
    // With the cause where the driver saw one (a full disk, no permission): "cannot create" alone left the
    // reader guessing (a review, 2026-11-28).
    const hid_t id = H5Fcreate(path.c_str(), H5F_ACC_TRUNC, fcpl.get(), fapl.get());
    if (id < 0 && !ordered_file_failure().empty())
        throw std::runtime_error("HDF5: cannot create " + path + " (" + ordered_file_failure() + ")");
    return Handle(id, H5Fclose, "create " + path);
}

void flush(hid_t file) {
    if (H5Fflush(file, H5F_SCOPE_GLOBAL) < 0)
        throw std::runtime_error("HDF5: cannot write the record to its file (" +
                                 (ordered_file_failure().empty() ? std::string("see HDF5") : ordered_file_failure()) +
                                 "); it holds everything written before");
}

namespace {
// The type of the record's strings (datasets and attributes): variable-length UTF-8.
Handle utf8_string_type() {
    Handle type(H5Tcopy(H5T_C_S1), H5Tclose, "copy type");
    check(H5Tset_size(type.get(), H5T_VARIABLE), "make a string type", 0);
    check(H5Tset_cset(type.get(), H5T_CSET_UTF8), "make a string type", 0);
    return type;
}
}  // namespace

void write_string(hid_t parent, const std::string& name, const std::string& text) {
    const Handle type = utf8_string_type();
    Handle space(H5Screate(H5S_SCALAR), H5Sclose, "create space");
    create_groups(parent, parent_of(name));
    Handle ds(H5Dcreate2(parent, name.c_str(), type.get(), space.get(), H5P_DEFAULT, H5P_DEFAULT, H5P_DEFAULT), H5Dclose,
              "create " + name);
    const char* p = text.c_str();
    check(H5Dwrite(ds.get(), type.get(), H5S_ALL, H5S_ALL, H5P_DEFAULT, &p), "write " + name, 0);
}

namespace {
// An attribute that exists with the same type is written over in place: deleting it and creating it again
// rewrites the object header in two steps (a kill in between lost the attribute) and frees header space.
void write_attribute(hid_t object, const std::string& name, hid_t file_type, hid_t memory_type, const void* value) {
    if (H5Aexists(object, name.c_str()) > 0) {
        Handle attr(H5Aopen(object, name.c_str(), H5P_DEFAULT), H5Aclose, "open attribute " + name);
        Handle stored(H5Aget_type(attr.get()), H5Tclose, "get the type of attribute " + name);
        if (H5Tequal(stored.get(), file_type) > 0) {
            check(H5Awrite(attr.get(), memory_type, value), "write attribute " + name, 0);
            return;
        }
        attr.reset();
        check(H5Adelete(object, name.c_str()), "replace attribute " + name, 0);
    }
    Handle space(H5Screate(H5S_SCALAR), H5Sclose, "create space");
    Handle attr(H5Acreate2(object, name.c_str(), file_type, space.get(), H5P_DEFAULT, H5P_DEFAULT), H5Aclose,
                "create attribute " + name);
    check(H5Awrite(attr.get(), memory_type, value), "write attribute " + name, 0);
}
}  // namespace

void set_attribute(hid_t object, const std::string& name, const std::string& value) {
    const Handle type = utf8_string_type();
    const char* p = value.c_str();
    write_attribute(object, name, type.get(), type.get(), &p);
}

std::string string_attribute(hid_t object, const std::string& name) {
    if (H5Aexists(object, name.c_str()) <= 0) return {};
    Handle attr(H5Aopen(object, name.c_str(), H5P_DEFAULT), H5Aclose, "open attribute " + name);
    Handle stored(H5Aget_type(attr.get()), H5Tclose, "type of attribute " + name);
    if (H5Tget_class(stored.get()) != H5T_STRING || H5Tis_variable_str(stored.get()) <= 0) return {};
    const Handle type = utf8_string_type();
    char* text = nullptr;
    if (H5Aread(attr.get(), type.get(), &text) < 0 || !text) return {};
    std::string out(text);
    H5free_memory(text);
    return out;
}

void set_attribute(hid_t object, const std::string& name, double value) {
    write_attribute(object, name, H5T_IEEE_F64LE, H5T_NATIVE_DOUBLE, &value);
}

void set_attribute(hid_t object, const std::string& name, std::int64_t value) {
    write_attribute(object, name, H5T_STD_I64LE, H5T_NATIVE_INT64, &value);
}

void create_groups(hid_t parent, const std::string& path) {
    Handle gcpl(H5Pcreate(H5P_GROUP_CREATE), H5Pclose, "create group creation properties");
    check(H5Pset_local_heap_size_hint(gcpl.get(), kNameHeapBytes), "size a group's name heap", 0);
    for (std::size_t end = path.find('/', 1); ; end = path.find('/', end + 1)) {
        const std::string prefix = path.substr(0, end);
        if (!prefix.empty() && prefix != "/" && !exists(parent, prefix))
            Handle(H5Gcreate2(parent, prefix.c_str(), H5P_DEFAULT, gcpl.get(), H5P_DEFAULT), H5Gclose, "create group " + prefix);
        if (end == std::string::npos) break;
    }
}

bool exists(hid_t parent, const std::string& path) {
    // Walk the path one link at a time: H5Lexists fails on missing intermediate groups.
    std::string prefix;
    std::size_t pos = 0;
    while (pos <= path.size()) {
        std::size_t slash = path.find('/', pos);
        prefix = path.substr(0, slash);
        if (!prefix.empty() && H5Lexists(parent, prefix.c_str(), H5P_DEFAULT) <= 0) return false;
        if (slash == std::string::npos) break;
        pos = slash + 1;
    }
    return true;
}

std::vector<std::string> children(hid_t file, const std::string& group) {
    std::vector<std::string> names;
    if (!exists(file, group)) return names;
    check(H5Literate_by_name(
              file, group.c_str(), H5_INDEX_NAME, H5_ITER_INC, nullptr,
              [](hid_t, const char* name, const H5L_info_t*, void* out) noexcept -> herr_t {
                  try {  // nothing may be thrown through HDF5's C frames
                      static_cast<std::vector<std::string>*>(out)->push_back(name);
                      return 0;
                  } catch (...) {
                      return -1;
                  }
              },
              &names, H5P_DEFAULT),
          "list " + group, 0);
    return names;
}

void copy_object(hid_t source, hid_t target, const std::string& path) {
    check(H5Ocopy(source, path.c_str(), target, path.c_str(), H5P_DEFAULT, H5P_DEFAULT), "copy " + path, 0);
}

void copy_root_attributes(hid_t source, hid_t target) {
    // The callback runs inside HDF5's C code, which nothing may be thrown through: a failure is kept and
    // rethrown once the iteration has returned.
    struct Copy {
        hid_t target;
        std::exception_ptr failure;
    } copy{target, nullptr};
    const herr_t rc = H5Aiterate2(
        source, H5_INDEX_NAME, H5_ITER_NATIVE, nullptr,
        [](hid_t loc, const char* name, const H5A_info_t*, void* out) noexcept -> herr_t {
            auto& c = *static_cast<Copy*>(out);
            try {
                Handle attr(H5Aopen(loc, name, H5P_DEFAULT), H5Aclose, std::string("open attribute ") + name);
                Handle type(H5Aget_type(attr.get()), H5Tclose, "attribute type");
                Handle space(H5Aget_space(attr.get()), H5Sclose, "attribute space");
                Handle dst(H5Acreate2(c.target, name, type.get(), space.get(), H5P_DEFAULT, H5P_DEFAULT), H5Aclose,
                           std::string("create attribute ") + name);
                std::vector<unsigned char> buf(H5Tget_size(type.get()) *
                                               static_cast<std::size_t>(H5Sget_simple_extent_npoints(space.get())));
                check(H5Aread(attr.get(), type.get(), buf.data()), std::string("read attribute ") + name, 0);
                const herr_t written = H5Awrite(dst.get(), type.get(), buf.data());
                if (H5Tis_variable_str(type.get()) > 0) H5Dvlen_reclaim(type.get(), space.get(), H5P_DEFAULT, buf.data());
                check(written, std::string("write attribute ") + name, 0);
                return 0;
            } catch (...) {
                c.failure = std::current_exception();
                return -1;
            }
        },
        &copy);
    if (copy.failure) std::rethrow_exception(copy.failure);
    check(rc, "copy the root attributes", 0);
}

}  // namespace sphfsi::coordinator::h5
