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
    // `append`: continue an existing file (resume), dropping rows after `resume_t`.
    Watchpoints(const std::filesystem::path& file, const Value& scene, const protocol::InterfaceMesh& mesh,
                bool append, double resume_t);
    void write(double t, const protocol::F64Array& displacement);
    bool empty() const { return points_.empty(); }
    // Throws std::runtime_error if any row since the last flush could not be written (a full disk).
    void flush();

private:
    struct Point {
        std::string name;
        double x, y;
        protocol::MappedPoint where;
    };
    std::vector<Point> points_;
    std::filesystem::path file_;
    std::ofstream out_;
};

}  // namespace sphfsi::coordinator
