#pragma once
// One HDF5 file per run (layout in docs/record.md). Per-window rows are buffered and written with
// every frame; the file is flushed after every frame so a run killed at any moment keeps every
// completed frame. An XDMF sidecar lets ParaView open the fluid frames.
#include <filesystem>
#include <map>
#include <memory>
#include <optional>
#include <set>
#include <stdexcept>
#include <string>
#include <vector>

#include "sphfsi/coordinator/h5.hpp"
#include "sphfsi/coordinator/replace_file.hpp"
#include "sphfsi/protocol/arrays.hpp"
#include "sphfsi/protocol/value.hpp"

namespace sphfsi::coordinator {

struct RunMetadata {
    std::string scene_file, scene_text, overrides, software_version, git_revision;
    std::uint32_t protocol_version = 0;
};

// A name that can be an HDF5 dataset or attribute name as it is, and reads the same in h5py, ParaView and a
// shell: letters, digits, '_', '-', '.', '+', not starting with '.'. Participants choose the names of their
// FRAME fields, READY info and ADVANCED stats, so the rule is checked, never assumed.
bool plain_name(const std::string& name);
// The rule, as the refusals state it.
inline constexpr const char* kPlainNameRule = "1 to 128 bytes of ASCII letters, digits, _ - . +; not starting with '.'";
// Bounds on what a participant may ask the record to hold as attributes and window columns. HDF5 adds each
// as an object-header entry at a cost that grows with those already there: 200,000 READY info keys froze the
// coordinator (deaf to SIGINT, in the HDF5 library) for minutes. Ours send a dozen or two.
inline constexpr std::size_t kMaxInfoEntries = 256;   // READY info entries, nested ones counted
inline constexpr std::size_t kMaxInfoString = 4096;   // bytes of one READY info string
inline constexpr std::size_t kMaxStats = 256;         // ADVANCED stats names per participant

// What a participant sent cannot be recorded as it is (a field name HDF5 cannot hold, a field set or shape
// that changed between frames, ...). Thrown before anything is written, so the record stays consistent; the
// run turns it into a failure naming the participant.
class RecordRefused : public std::runtime_error {
public:
    using std::runtime_error::runtime_error;
};

// The `status` attribute of the record at `file` ("completed", "running", ...); empty when unreadable.
std::string record_status(const std::filesystem::path& file);

class Recorder {
public:
    // Creates `file` (replacing it), or with `resume_at` copies what it holds up to that time into FILE.resuming,
    // which records the resumed run and replaces `file` once the run reaches the time `file` ends at.
    Recorder(std::filesystem::path file, const RunMetadata& meta, std::optional<double> resume_at = std::nullopt);
    ~Recorder();

    // A resume's copy replaces `file` when `t` has reached the time the interrupted record ends at (the XDMF
    // sidecar is written then: until then it describes the interrupted record).
    void take_over_when_caught_up(double t);
    bool resume_pending() const { return resuming_.pending(); }
    bool resume_rename_failed() const { return resuming_.rename_failed(); }
    double history_end() const { return resuming_.end(); }
    // Closes and removes a resume's copy that has not replaced `file`, which stays as the interrupted run left
    // it; a copy whose rename failed is closed and kept (ResumeCopy::abandon).
    void abandon_resume();

    // Throws RecordRefused, writing nothing, on an `info` key that is not a plain name (see append_frame).
    void set_participant(const std::string& role, const std::string& software, const Value& info);
    void set_interface(const protocol::InterfaceMesh& mesh);

    // One coupling window: named scalar columns and the interface state. The columns are those of the first
    // window (an HDF5 dataset per name, a row per window): a later window's missing names are recorded as
    // NaN, and names it adds are not recorded. Returns those added names, each only the first time it is seen.
    std::vector<std::string> append_window(const std::vector<std::pair<std::string, double>>& columns,
                       const protocol::F64Array* displacement, const protocol::F64Array* force);
    // Throws RecordRefused, writing nothing, unless every name is a plain name (letters, digits, '_', '-',
    // '.', '+'; not starting with '.'; not "time", which the recorder writes) and the fields are those of the
    // role's first frame with the same shapes and types.
    void append_frame(const std::string& role, double t, const protocol::Fields& fields);
    // "running", "completed", "failed: ...", "interrupted". Writes the rows still buffered, then the XDMF sidecar
    // whole, then the status; returns the status written: "completed" becomes "failed: ..." when the sidecar
    // cannot be written.
    std::string set_status(const std::string& status);
    void set_number(const std::string& name, double value);  // a root attribute (totals, CPU use)
    void set_text(const std::string& name, const std::string& value);
    void flush();                                // writes buffered windows and flushes the file

    std::size_t frames(const std::string& role) const;
    double window_column_sum(const std::string& name);  // over every window recorded so far (0: no such column)
    const std::filesystem::path& file() const { return file_; }

private:
    void write_xdmf(const std::string& role);
    void copy_history(const std::filesystem::path& old_file, double until);
    h5::Series* existing_series(const std::string& path);  // opened or in the file already; nullptr if neither
    h5::Series& series(const std::string& path, const std::vector<hsize_t>& row_shape, bool is_int, hsize_t chunk_rows);

    std::filesystem::path file_;
    ResumeCopy resuming_;  // a resume's copy while it has not replaced file_; its end: the record's last time
    h5::Handle h5_;
    std::map<std::string, h5::Series> series_;
    std::vector<std::string> window_columns_;
    std::set<std::string> unrecorded_columns_;  // names first seen after the first window
    std::vector<std::vector<double>> window_buffer_;  // per column
    std::vector<double> disp_buffer_, force_buffer_;
    hsize_t interface_rows_buffered_ = 0;
    std::uint64_t interface_vertices_ = 0;
    std::map<std::string, std::vector<double>> frame_times_;
    std::map<std::string, std::set<std::string>> frame_fields_;  // role -> the field names of its first frame
};

}  // namespace sphfsi::coordinator
