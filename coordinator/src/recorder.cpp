#include "sphfsi/coordinator/recorder.hpp"

#include <algorithm>
#include <cctype>
#include <limits>
#include <set>
#include <sstream>
#include <stdexcept>

#include "sphfsi/coordinator/replace_file.hpp"
#include "sphfsi/protocol/codec.hpp"

namespace sphfsi::coordinator {
namespace {
std::vector<hsize_t> row_shape_of(const std::vector<std::uint64_t>& shape) { return {shape.begin(), shape.end()}; }
}  // namespace

bool plain_name(const std::string& name) {
    if (name.empty() || name.size() > 128 || name[0] == '.') return false;
    for (char c : name)
        if (!(std::isalnum(static_cast<unsigned char>(c)) || c == '_' || c == '-' || c == '.' || c == '+')) return false;
    return true;
}

namespace {

// Rows of a per-window column's chunk: 512 float64 = 4 kB. Uncompressed chunks are allocated whole, so a
// short run's ~30 columns at 4096 rows a chunk took 1 MB for a few dozen rows (1.0 of a 2.2 MB dam-break
// record at a/10). Rows are still buffered up to kWindowRowsBuffered between frames.
constexpr hsize_t kWindowChunkRows = 512;
constexpr std::size_t kWindowRowsBuffered = 4096;

std::string quoted(const std::string& name) { return "'" + protocol::printable(name, 64) + "'"; }

// The record's strings are HDF5 variable-length UTF-8, which end at a NUL: text that is not UTF-8 made every
// attribute of its group unreadable to h5py (UnicodeDecodeError), and a NUL cut the rest of the text off
// without a word (a review, 2026-11-28). A peer's text is refused rather than escaped: the record keeps what
// was sent, or nothing.
bool record_text(const std::string& s) { return protocol::is_utf8(s) && s.find('\0') == std::string::npos; }
constexpr const char* kRecordTextRule = "which is not UTF-8 text without NUL bytes (the record's strings are UTF-8 and end at a NUL)";

// Every entry of the (nested) table is recorded as one attribute named by its dotted path: a value the
// record cannot hold, or two entries that would land on one name (`a.b` and `a = {b}`, or `software`, the
// HELLO's), would lose one of them without a word. `names` collects the attribute names.
void check_info_keys(const std::string& prefix, const Value& v, std::set<std::string>& names) {
    for (const auto& [k, x] : v.as_table()) {
        if (!plain_name(k))
            throw RecordRefused("sent READY info key " + quoted(prefix + k) +
                                ", which is not a plain name (" + kPlainNameRule + ")");
        if (names.size() > kMaxInfoEntries)  // `names` starts with the HELLO's software
            throw RecordRefused("sent more than " + std::to_string(kMaxInfoEntries) + " READY info entries");
        if (x.is_string() && x.as_string().size() > kMaxInfoString)
            throw RecordRefused("sent READY info " + quoted(prefix + k) + " of " + std::to_string(x.as_string().size()) +
                                " bytes; at most " + std::to_string(kMaxInfoString));
        if (x.is_string() && !record_text(x.as_string()))
            throw RecordRefused("sent READY info " + quoted(prefix + k) + " = '" + protocol::printable(x.as_string(), 64) +
                                "', " + kRecordTextRule);
        if (!(x.is_number() || x.is_string() || x.is_bool() || x.is_table()))
            throw RecordRefused("sent READY info " + quoted(prefix + k) + " as " + x.type_name() +
                                "; allowed: a number, string, boolean or map");
        if (!names.insert(prefix + k).second)
            throw RecordRefused("sent READY info " + quoted(prefix + k) + " twice (a dotted key and a nested map, or "
                                "the HELLO's 'software')");
        if (x.is_table()) check_info_keys(prefix + k + ".", x, names);
    }
}

void write_value_attributes(hid_t object, const std::string& prefix, const Value& v) {
    if (!v.is_table()) return;
    for (const auto& [k, x] : v.as_table()) {
        std::string name = prefix.empty() ? k : prefix + "." + k;
        // Numbers keep the type they were sent with: an integer (a particle count) is read back as one, and
        // one beyond 2^53 keeps every digit. A boolean is an integer 0 or 1 (HDF5 has no boolean type).
        if (x.is_int()) h5::set_attribute(object, name, x.as_int());
        else if (x.is_number()) h5::set_attribute(object, name, x.as_double());
        else if (x.is_string()) h5::set_attribute(object, name, x.as_string());
        else if (x.is_bool()) h5::set_attribute(object, name, std::int64_t{x.as_bool() ? 1 : 0});
        else if (x.is_table()) write_value_attributes(object, name, x);
    }
}
}  // namespace

std::string record_status(const std::filesystem::path& file) {
    H5Eset_auto2(H5E_DEFAULT, nullptr, nullptr);
    const hid_t f = H5Fopen(file.c_str(), H5F_ACC_RDONLY, H5P_DEFAULT);
    if (f < 0) return {};
    h5::Handle h(f, H5Fclose, "open " + file.string());
    return h5::string_attribute(f, "status");
}

Recorder::Recorder(std::filesystem::path file, const RunMetadata& meta, std::optional<double> resume_at)
    : file_(std::move(file)) {
    H5Eset_auto2(H5E_DEFAULT, nullptr, nullptr);  // we report HDF5 failures ourselves
    if (!resume_at) {
        // Built beside its name, which it takes once it reads back: the first flush writes the superblock
        // before the root group (ordered_file.cpp), so a kill inside it would leave a file no reader opens.
        auto creating = file_;
        creating += ".creating";
        std::filesystem::remove(file_);  // a kill from here on leaves no record, never an earlier run's
        h5_ = h5::create_file(creating.string());
        h5::write_string(h5_.get(), "scene", meta.scene_text);
        h5::set_attribute(h5_.get(), "scene_file", meta.scene_file);
        h5::set_attribute(h5_.get(), "overrides", meta.overrides);
        h5::set_attribute(h5_.get(), "software_version", meta.software_version);
        h5::set_attribute(h5_.get(), "git_revision", meta.git_revision);
        h5::set_attribute(h5_.get(), "protocol_version", static_cast<std::int64_t>(meta.protocol_version));
        set_status("running");
        flush();
        std::filesystem::rename(creating, file_);  // the open handle follows the file: it is the same inode
        return;
    }
    // The interrupted run may have been killed in the middle of a write, so its file is not appended to:
    // what it holds up to the checkpoint is copied into a new file beside it, which takes the rest of the run
    // and replaces record.h5 in one rename once it reaches the time record.h5 ends at (take_over_when_caught_up).
    // Until then record.h5 holds more than the copy: a resume that fails, is stopped or is killed before it
    // leaves record.h5 as it was (and, killed, a stale record.h5.resuming, replaced by the next try); after
    // it, record.h5 holds the history and everything since. Builds before 2026-11-25 renamed record.h5 to
    // record.h5.interrupted first, so a resume of theirs that died left the history in that file: refuse to
    // guess which file is whole.
    auto interrupted = file_;
    interrupted += ".interrupted";
    if (std::filesystem::exists(interrupted))
        throw std::runtime_error(interrupted.string() + " is left from a resume that did not finish and may hold history that " +
                                 file_.string() + " lacks: keep the file you want as " + file_.filename().string() +
                                 ", remove the other, and resume again");
    if (!std::filesystem::is_regular_file(file_))
        throw std::runtime_error("cannot resume: " + file_.string() + " is missing; the checkpoint continues that record, " +
                                 "so without it start a new run");
    resuming_.begin(file_);
    try {
        h5_ = h5::create_file(resuming_.path().string());
        copy_history(file_, *resume_at);
        // The copied attributes name the build that started the run; a resume may run another build.
        h5::set_attribute(h5_.get(), "resumed_by", meta.software_version + " (" + meta.git_revision + ")");
        set_status("running (resumed)");
        flush();
    } catch (const std::exception& e) {
        abandon_resume();  // record.h5 stays as the interrupted run left it, and no copy is left beside it
        throw std::runtime_error("cannot resume from " + file_.string() + ": " + e.what());
    }
}

void Recorder::take_over_when_caught_up(double t) {
    if (!resuming_.caught_up(t)) return;
    flush();
    resuming_.replace(file_);
    for (const auto& [role, times] : frame_times_)
        if (series_.count("/frames/" + role + "/position")) write_xdmf(role);
}

void Recorder::abandon_resume() {
    if (!resuming_.pending()) return;
    series_.clear();  // the datasets first: HDF5 keeps a file open while any of its objects is
    h5_.reset();
    resuming_.abandon();
}

// Copies the interrupted run's record up to time `until`: the scene, participants and root attributes
// whole; windows, interface history and frames row by row, up to the last one at or before `until`.
void Recorder::copy_history(const std::filesystem::path& old_file, double until) {
    if (H5Fis_hdf5(old_file.c_str()) <= 0)  // H5Fis_accessible from HDF5 1.12; Debian 12 has 1.10
        throw std::runtime_error("it is not an HDF5 file that can be read (damaged, or not a record)");
    h5::Handle src(H5Fopen(old_file.c_str(), H5F_ACC_RDONLY, H5P_DEFAULT), H5Fclose, "open " + old_file.string());
    for (const char* path : {"/scene", "/participants"})
        if (h5::exists(src.get(), path)) h5::copy_object(src.get(), h5_.get(), path);
    h5::copy_root_attributes(src.get(), h5_.get());
    auto read_all = [&](const std::string& path) {
        h5::Series s(src.get(), path);
        std::vector<double> v(s.rows());
        s.read(v.data(), s.rows());
        return v;
    };
    auto rows_until = [&](const std::string& time_path) -> hsize_t {
        if (!h5::exists(src.get(), time_path)) return 0;
        std::vector<double> t = read_all(time_path);
        for (double x : t)  // the largest, not the last: a kill can leave a row extended but unwritten (0)
            resuming_.holds(x);
        // Rows in time order up to `until`: a row a kill left extended but unwritten reads 0 and ends them.
        hsize_t keep = 0;
        while (keep < t.size() && t[keep] <= until * (1 + 1e-12) && (keep == 0 || t[keep] > t[keep - 1])) ++keep;
        return keep;
    };
    // In blocks of at most 64 MiB: a whole dataset at once is 3.2 GB of positions for 100,000 particles and
    // 2,000 frames (a review, 2026-11-27).
    auto copy_rows = [&](const std::string& path, hsize_t keep, hsize_t chunk_rows) {
        h5::Series s(src.get(), path);
        keep = std::min(keep, s.rows());
        h5::Series& to = series(path, s.row_shape(), s.is_int(), chunk_rows);
        const hsize_t block = std::max<hsize_t>(1, (hsize_t{64} << 20) / std::max<hsize_t>(1, s.row_bytes()));
        std::vector<unsigned char> buf(std::min(keep, block) * s.row_bytes());
        for (hsize_t from = 0; from < keep; from += block) {
            const hsize_t rows = std::min(block, keep - from);
            s.read(buf.data(), rows, from);
            to.append(buf.data(), rows);
        }
    };
    // A kill during a flush can leave the datasets of one table a row apart (HDF5 updates them one after
    // another): keep only the rows every one of them has, so the copy is one consistent table again.
    auto rows_in_all = [&](const std::string& group, hsize_t keep, const std::vector<std::string>& skip) {
        for (const auto& name : h5::children(src.get(), group))
            if (std::find(skip.begin(), skip.end(), name) == skip.end()) keep = std::min(keep, h5::Series(src.get(), group + "/" + name).rows());
        return keep;
    };
    hsize_t windows = rows_in_all("/windows", rows_until("/windows/t"), {});
    if (h5::exists(src.get(), "/interface")) windows = rows_in_all("/interface", windows, {"vertices", "cells"});
    for (const auto& name : h5::children(src.get(), "/windows")) copy_rows("/windows/" + name, windows, kWindowChunkRows);
    // The columns stay those the interrupted run chose at its first window (append_window): chosen again from
    // the first window after the resume, a name that had appeared late would start a column of its own,
    // rows short, and the next resume would cut every column to it.
    window_columns_ = h5::children(src.get(), "/windows");
    window_buffer_.assign(window_columns_.size(), {});
    for (const auto& name : h5::children(src.get(), "/interface")) {
        const std::string path = "/interface/" + name;
        bool mesh = name == "vertices" || name == "cells";
        h5::Series s(src.get(), path);
        copy_rows(path, mesh ? s.rows() : windows, mesh ? std::max<hsize_t>(s.rows(), 1) : 64);
        if (name == "vertices") interface_vertices_ = s.rows();
    }
    for (const auto& role : h5::children(src.get(), "/frames")) {
        const std::string group = "/frames/" + role + "/";
        const hsize_t frames = rows_in_all("/frames/" + role, rows_until(group + "time"), {});
        for (const auto& name : h5::children(src.get(), "/frames/" + role))
            copy_rows(group + name, frames, name == "time" ? 256 : 1);
        std::vector<double> times = read_all(group + "time");
        frame_times_[role].assign(times.begin(), times.begin() + static_cast<std::ptrdiff_t>(frames));
        for (const auto& name : h5::children(src.get(), "/frames/" + role))
            if (name != "time") frame_fields_[role].insert(name);
        if (series_.count(group + "position")) write_xdmf(role);  // the sidecar may list frames dropped here
    }
    flush();
}

double Recorder::window_column_sum(const std::string& name) {
    double sum = 0.0;
    if (const h5::Series* s = existing_series("/windows/" + name)) {
        std::vector<double> rows(s->rows());
        s->read(rows.data(), s->rows());
        for (double v : rows) sum += v;
    }
    const auto column = std::find(window_columns_.begin(), window_columns_.end(), name);
    if (column != window_columns_.end())
        for (double v : window_buffer_[static_cast<std::size_t>(column - window_columns_.begin())]) sum += v;
    return sum;
}

Recorder::~Recorder() {
    try {
        flush();
    } catch (...) {
    }
}

h5::Series* Recorder::existing_series(const std::string& path) {
    if (auto it = series_.find(path); it != series_.end()) return &it->second;
    if (h5::exists(h5_.get(), path)) return &series_.emplace(path, h5::Series(h5_.get(), path)).first->second;
    return nullptr;
}

h5::Series& Recorder::series(const std::string& path, const std::vector<hsize_t>& row_shape, bool is_int, hsize_t chunk_rows) {
    if (h5::Series* s = existing_series(path)) return *s;
    // Compressed: integer frame fields only (one frame per chunk, written once). Deflate shrinks float fields
    // 1.3-1.6 times at ~9 ms per 17k-particle frame while both participants wait (docs/record.md).
    const bool compress = chunk_rows == 1 && is_int;
    return series_.emplace(path, h5::Series(h5_.get(), path, row_shape, is_int, chunk_rows, compress)).first->second;
}

void Recorder::set_participant(const std::string& role, const std::string& software, const Value& info) {
    std::set<std::string> names{"software"};
    if (!record_text(software))
        throw RecordRefused("says in HELLO that it is software '" + protocol::printable(software, 64) + "', " + kRecordTextRule);
    if (info.is_table()) check_info_keys("", info, names);
    std::string path = "/participants/" + role;
    h5::create_groups(h5_.get(), path);
    h5::Handle g(H5Gopen2(h5_.get(), path.c_str(), H5P_DEFAULT), H5Gclose, "open " + path);
    h5::set_attribute(g.get(), "software", software);
    write_value_attributes(g.get(), "", info);
}

void Recorder::set_interface(const protocol::InterfaceMesh& mesh) {
    interface_vertices_ = mesh.vertices.rows();
    if (h5::exists(h5_.get(), "/interface/vertices")) return;
    // One chunk holds the whole mesh; HDF5 cannot chunk by 0 rows (a structure alone with no wetted member).
    const hsize_t vertices = std::max<hsize_t>(mesh.vertices.rows(), 1), cells = std::max<hsize_t>(mesh.cells.rows(), 1);
    series("/interface/vertices", {2}, false, vertices).append(mesh.vertices.values.data(), mesh.vertices.rows());
    series("/interface/cells", {4}, true, cells).append(mesh.cells.values.data(), mesh.cells.rows());
}

std::vector<std::string> Recorder::append_window(const std::vector<std::pair<std::string, double>>& columns,
                                                 const protocol::F64Array* displacement, const protocol::F64Array* force) {
    if (window_columns_.empty()) {
        for (const auto& [name, v] : columns) window_columns_.push_back(name);
        window_buffer_.resize(window_columns_.size());
    }
    std::vector<std::string> unrecorded;
    for (std::size_t i = 0; i < columns.size(); ++i)
        if ((i >= window_columns_.size() || columns[i].first != window_columns_[i]) &&
            std::find(window_columns_.begin(), window_columns_.end(), columns[i].first) == window_columns_.end() &&
            unrecorded_columns_.insert(columns[i].first).second)
            unrecorded.push_back(columns[i].first);
    // The columns are those of the first window; a later window's extra names are dropped and its
    // missing ones recorded as NaN, so every column keeps one row per window.
    for (std::size_t i = 0; i < window_columns_.size(); ++i) {
        double value = std::numeric_limits<double>::quiet_NaN();
        if (i < columns.size() && columns[i].first == window_columns_[i]) value = columns[i].second;
        else
            for (const auto& [name, v] : columns)
                if (name == window_columns_[i]) value = v;
        window_buffer_[i].push_back(value);
    }
    if (displacement && force && interface_vertices_) {
        disp_buffer_.insert(disp_buffer_.end(), displacement->values.begin(), displacement->values.end());
        force_buffer_.insert(force_buffer_.end(), force->values.begin(), force->values.end());
        ++interface_rows_buffered_;
    }
    // Bound memory between frames: write out long stretches without a frame.
    if (window_buffer_[0].size() >= kWindowRowsBuffered) flush();
    return unrecorded;
}

void Recorder::append_frame(const std::string& role, double t, const protocol::Fields& fields) {
    const std::string group = "/frames/" + role + "/";
    // Every check before the first write: each field's rows must stay aligned with /frames/ROLE/time.
    auto is_int_field = [](const protocol::Field& f) { return std::holds_alternative<protocol::I32Array>(f); };
    auto shape_of = [](const protocol::Field& f) { return std::visit([](const auto& a) { return row_shape_of(a.shape); }, f); };
    std::set<std::string> names;
    for (const auto& [name, field] : fields) {
        if (!plain_name(name) || name == "time")
            throw RecordRefused("sent a FRAME field named " + quoted(name) +
                                ", which is not a plain name (" + kPlainNameRule + "; not 'time')");
        names.insert(name);
        // A frame is one row of a chunked dataset whose chunk is that row: HDF5 cannot chunk an empty one.
        if (const auto shape = shape_of(field); std::find(shape.begin(), shape.end(), 0) != shape.end()) {
            std::string dims;
            for (auto d : shape) dims += (dims.empty() ? "" : ", ") + std::to_string(d);
            throw RecordRefused("sent the FRAME field '" + name + "' of shape [" + dims + "]: every dimension must be at least 1");
        }
    }
    auto first = frame_fields_.find(role);
    if (first == frame_fields_.end()) {
        frame_fields_[role] = names;
    } else if (first->second != names) {
        std::string was, now;
        for (const auto& n : first->second) was += (was.empty() ? "" : ", ") + n;
        for (const auto& n : names) now += (now.empty() ? "" : ", ") + n;
        throw RecordRefused("changed its FRAME fields from [" + was + "] to [" + now + "]; every frame must send the same fields");
    }
    for (const auto& [name, field] : fields)
        if (const h5::Series* known = existing_series(group + name);
            known && (known->row_shape() != shape_of(field) || known->is_int() != is_int_field(field)))
            throw RecordRefused("changed the shape or type of FRAME field '" + name + "' between frames");
    for (const auto& [name, field] : fields)
        std::visit([&](const auto& a) { series(group + name, shape_of(field), is_int_field(field), 1).append(a.values.data(), 1); }, field);
    series(group + "time", {}, false, 256).append(&t, 1);
    frame_times_[role].push_back(t);
    flush();
    // The sidecar is rewritten whole (atomically), so rewriting it at every frame cost writes growing with the
    // square of the frame count (2.5 KB a frame: 125 GB over 10,000 frames, a review, 2026-11-27). It is
    // rewritten at each of the first 100 frames, then at every (frames / 100)-th, and when the status is set.
    const std::size_t frames = frame_times_[role].size();
    if (fields.count("position") && (frames <= 100 || frames % (frames / 100) == 0)) write_xdmf(role);
}

std::size_t Recorder::frames(const std::string& role) const {
    auto it = series_.find("/frames/" + role + "/time");
    return it == series_.end() ? 0 : it->second.rows();
}

// The rows still buffered reach the file first, then the status: a kill between the two flushes leaves a
// status that describes no more than the rows on disk ("completed" once came out one flush before the last
// windows, a review, 2026-11-27).
std::string Recorder::set_status(const std::string& status) {
    flush();
    std::string written = status;
    try {
        if (series_.count("/frames/fluid/position")) write_xdmf("fluid");  // every frame, whatever the throttle skipped
    } catch (const std::exception& e) {
        // A run that completed has not, if its sidecar cannot be written; a run already stopped keeps its cause.
        if (status == "completed") written = std::string("failed: ") + e.what();
    }
    h5::set_attribute(h5_.get(), "status", written);
    h5::flush(h5_.get());
    return written;
}

void Recorder::set_number(const std::string& name, double value) { h5::set_attribute(h5_.get(), name, value); }
void Recorder::set_text(const std::string& name, const std::string& value) { h5::set_attribute(h5_.get(), name, value); }

void Recorder::flush() {
    if (!h5_) return;  // an abandoned resume's copy, removed
    if (!window_columns_.empty() && !window_buffer_[0].empty()) {
        for (std::size_t i = 0; i < window_columns_.size(); ++i) {
            series("/windows/" + window_columns_[i], {}, false, kWindowChunkRows).append(window_buffer_[i].data(), window_buffer_[i].size());
            window_buffer_[i].clear();
        }
    }
    if (interface_rows_buffered_) {
        series("/interface/displacement", {interface_vertices_, 2}, false, 64).append(disp_buffer_.data(), interface_rows_buffered_);
        series("/interface/force", {interface_vertices_, 2}, false, 64).append(force_buffer_.data(), interface_rows_buffered_);
        disp_buffer_.clear();
        force_buffer_.clear();
        interface_rows_buffered_ = 0;
    }
    h5::flush(h5_.get());
}

// XDMF 3 sidecar: a temporal collection of point clouds read straight from the HDF5 datasets. It describes
// the fluid's frames alone (docs/record.md): one file, so a foreign structure that also sends `position`
// must not replace it. Fields are the participant's own (docs/protocol.md lets it send any), so only what
// XDMF can say is listed: positions of 2 or 3 components (else no sidecar), per-particle scalars and
// vectors (a field with more axes is left out; it is still in record.h5).
void Recorder::write_xdmf(const std::string& role) {
    if (role != "fluid") return;
    if (resuming_.pending()) return;  // record.h5 is still the interrupted run's, which its sidecar describes
    const std::string group = "/frames/" + role + "/";
    const auto& pos = series_.at(group + "position");
    if (pos.row_shape().size() != 2 || (pos.row_shape()[1] != 2 && pos.row_shape()[1] != 3)) return;
    const hsize_t n = pos.row_shape()[0], dims = pos.row_shape()[1];
    const std::string h5name = file_.filename().string();
    // One row of a (frames, n, comps) dataset as an (n, comps) array; `comps` 0: a (frames, n) dataset, whose
    // rows are 1-D (a foreign participant may send such fields; declared with three axes, they read wrong).
    auto slab = [&](std::ostringstream& x, hsize_t row, const std::string& field, hsize_t comps, bool is_int) {
        x << "<DataItem ItemType=\"HyperSlab\" Dimensions=\"" << n;
        if (comps > 1) x << ' ' << comps;
        if (comps == 0)
            x << "\">\n<DataItem Dimensions=\"3 2\" Format=\"XML\">" << row << " 0 1 1 1 " << n
              << "</DataItem>\n<DataItem Dimensions=\"" << pos.rows() << ' ' << n;
        else
            x << "\">\n<DataItem Dimensions=\"3 3\" Format=\"XML\">" << row << " 0 0 1 1 1 1 " << n << ' ' << comps
              << "</DataItem>\n<DataItem Dimensions=\"" << pos.rows() << ' ' << n << ' ' << comps;
        x << "\" NumberType=\"" << (is_int ? "Int\" Precision=\"4" : "Float\" Precision=\"8") << "\" Format=\"HDF\">"
          << h5name << ':' << group << field << "</DataItem>\n</DataItem>\n";
    };
    std::ostringstream x;
    x.precision(17);  // frame times to the last bit: 6 digits merged frames 1 us apart late in a run
    x << "<?xml version=\"1.0\" ?>\n<Xdmf Version=\"3.0\">\n<Domain>\n<Grid Name=\"" << role
      << "\" GridType=\"Collection\" CollectionType=\"Temporal\">\n";
    const auto& times = frame_times_[role];
    for (std::size_t k = 0; k < times.size(); ++k) {
        const hsize_t row = k;
        x << "<Grid Name=\"frame" << row << "\" GridType=\"Uniform\">\n<Time Value=\"" << times[k]
          << "\"/>\n<Topology TopologyType=\"Polyvertex\" NumberOfElements=\"" << n
          << "\"/>\n<Geometry GeometryType=\"" << (dims == 2 ? "XY" : "XYZ") << "\">\n";
        slab(x, row, "position", dims, false);
        x << "</Geometry>\n";
        for (const auto& [path, s] : series_) {
            if (path.rfind(group, 0) != 0) continue;
            const std::string field = path.substr(group.size());
            if (field == "position" || field == "time" || s.row_shape().empty() || s.row_shape().size() > 2 ||
                s.row_shape()[0] != n)
                continue;
            const hsize_t comps = s.row_shape().size() > 1 ? s.row_shape()[1] : 0;
            // XDMF's Vector means 3 components; 2D vectors go in as Matrix (n x 2), read as 2-component arrays.
            x << "<Attribute Name=\"" << field << "\" AttributeType=\""
              << (comps <= 1 ? "Scalar" : comps == 3 ? "Vector" : "Matrix") << "\" Center=\"Node\">\n";
            slab(x, row, field, comps, s.is_int());
            x << "</Attribute>\n";
        }
        x << "</Grid>\n";
    }
    x << "</Grid>\n</Domain>\n</Xdmf>\n";
    auto out = file_;
    out.replace_extension(".xdmf");
    // Atomic, and checked: ParaView never reads half a file, and a full disk stops the run with the cause
    // instead of replacing a good sidecar with an empty one.
    replace_file(out, x.str(), "the XDMF sidecar");
}

}  // namespace sphfsi::coordinator
