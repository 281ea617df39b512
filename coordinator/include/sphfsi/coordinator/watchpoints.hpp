#pragma once
// watchpoints.csv: time, name, x, y, dx, dy of named structure points, located on the interface
// mesh and interpolated exactly as the fluid interpolates its boundary particles.
#include <filesystem>
#include <fstream>
#include <string>
#include <vector>

#include "sphfsi/protocol/mapping.hpp"
#include "sphfsi/protocol/value.hpp"

namespace sphfsi::coordinator {

class Watchpoints {
public:
    // `append`: continue an existing file (resume), dropping rows after `resume_t`, in FILE.resuming until
    // take_over() replaces the file with it (when the record's copy replaces record.h5).
    Watchpoints(const std::filesystem::path& file, const Value& scene, const protocol::InterfaceMesh& mesh,
                bool append, double resume_t);
    void write(double t, const protocol::F64Array& displacement);
    bool empty() const { return points_.empty(); }
    // Throws std::runtime_error if any row since the last flush could not be written (a full disk).
    void flush();
    void take_over();
    // Removes a resume's FILE.resuming that has not replaced the file, which stays as it was.
    void abandon_resume();

private:
    struct Point {
        std::string name;
        double x, y;
        protocol::MappedPoint where;
    };
    std::vector<Point> points_;
    std::filesystem::path file_;
    std::filesystem::path resuming_;  // a resume's rows while they have not replaced file_
    std::ofstream out_;
};

}  // namespace sphfsi::coordinator
