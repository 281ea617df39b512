#pragma once
// watchpoints.csv: time, name, x, y, dx, dy of named structure points, located on the interface
// mesh and interpolated exactly as the fluid interpolates its boundary particles.
#include <filesystem>
#include <fstream>
#include <string>
#include <vector>

#include "sphfsi/coordinator/replace_file.hpp"
#include "sphfsi/protocol/mapping.hpp"
#include "sphfsi/protocol/value.hpp"

namespace sphfsi::coordinator {

class Watchpoints {
public:
    // `append`: continue an existing file (resume), dropping rows after `resume_t`, in FILE.resuming until
    // take_over_when_caught_up() replaces the file with it.
    Watchpoints(const std::filesystem::path& file, const Value& scene, const protocol::InterfaceMesh& mesh,
                bool append, double resume_t);
    void write(double t, const protocol::F64Array& displacement);
    bool empty() const { return points_.empty(); }
    // Throws std::runtime_error if any row since the last flush could not be written (a full disk).
    void flush();
    // A resume's FILE.resuming replaces the file once `t` has reached the last time the file holds (its rows
    // run ahead of the record's, which is flushed at frames only).
    void take_over_when_caught_up(double t);
    bool resume_pending() const { return resuming_.pending(); }
    bool resume_rename_failed() const { return resuming_.rename_failed(); }
    double history_end() const { return resuming_.end(); }
    // Closes and removes a resume's FILE.resuming that has not replaced the file, which stays as it was (one
    // whose rename failed is kept: ResumeCopy::abandon).
    void abandon_resume();

private:
    struct Point {
        std::string name;
        double x, y;
        protocol::MappedPoint where;
    };
    std::vector<Point> points_;
    std::filesystem::path file_;
    ResumeCopy resuming_;  // a resume's rows while they have not replaced file_; its end: the file's last row
    std::ofstream out_;
};

}  // namespace sphfsi::coordinator
