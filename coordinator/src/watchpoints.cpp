#include "sphfsi/coordinator/watchpoints.hpp"

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <cstdlib>
#include <iterator>
#include <sstream>
#include <stdexcept>

#include "sphfsi/coordinator/replace_file.hpp"

namespace sphfsi::coordinator {

Watchpoints::Watchpoints(const std::filesystem::path& file, const Value& scene, const protocol::InterfaceMesh& mesh,
                         bool append, double resume_t)
    : file_(file) {
    if (const Value* list = scene.find("watchpoint")) {
        for (const Value& w : list->as_array()) {
            Point p{w.at("name").as_string(), w.at("x").as_double(), w.at("y").as_double(), {}};
            p.where = protocol::locate(mesh, p.x, p.y);
            if (p.where.cell < 0) throw ConfigError("watchpoint '" + p.name + "': the structure publishes no interface cells");
            // Outside its nearest cell the bilinear weights are clamped: the point follows the cell's nearest
            // edge. Within one cell size that is still a point of the structure; farther, a typo.
            double size = 0;
            for (int i = 0; i < 4; ++i)
                for (int j = i + 1; j < 4; ++j)
                    size = std::max(size, std::hypot(mesh.vertices(p.where.vertex[i], 0) - mesh.vertices(p.where.vertex[j], 0),
                                                     mesh.vertices(p.where.vertex[i], 1) - mesh.vertices(p.where.vertex[j], 1)));
            if (p.where.distance > size)
                throw ConfigError("watchpoint '" + p.name + "': (" + std::to_string(p.x) + ", " + std::to_string(p.y) +
                                  ") m lies " + std::to_string(p.where.distance) +
                                  " m from the structure's interface; allowed: within one cell size (" +
                                  std::to_string(size) + " m) of it");
            points_.push_back(p);
        }
    }
    if (points_.empty()) return;
    const char* header = "time,name,x,y,dx,dy\n";
    if (!append || !std::filesystem::exists(file)) {
        out_.open(file, std::ios::trunc);
        out_ << header;
        flush();
        return;
    }
    // A resume keeps the rows up to the checkpoint: whole rows only (a kill can cut the last one short), in
    // time order up to the first one beyond it. They go to FILE.resuming, which takes the resumed rows and
    // replaces the file once the run has passed the file's last row (take_over_when_caught_up): a resume stopped
    // before then leaves it as the interrupted run left it.
    std::ifstream in(file);
    std::string text((std::istreambuf_iterator<char>(in)), std::istreambuf_iterator<char>());
    std::string kept = header;
    std::size_t at = text.find('\n');
    bool keeping = true;
    for (std::size_t end; at != std::string::npos && (end = text.find('\n', at + 1)) != std::string::npos; at = end) {
        const std::string line = text.substr(at + 1, end - at - 1);
        char* stop = nullptr;
        const double t = std::strtod(line.c_str(), &stop);
        if (std::count(line.begin(), line.end(), ',') != 5 || stop == line.c_str() || *stop != ',') break;
        resuming_.holds(t);  // the file is replaced only once the run is past its last row
        keeping = keeping && t <= resume_t * (1 + 1e-12);
        if (keeping) kept += line + "\n";
    }
    resuming_.begin(file);
    replace_file(resuming_.path(), kept, "watchpoints");
    out_.open(resuming_.path(), std::ios::app);
    flush();
}

void Watchpoints::take_over_when_caught_up(double t) {
    if (!resuming_.caught_up(t)) return;
    flush();
    resuming_.replace(file_);
}

void Watchpoints::abandon_resume() {
    if (!resuming_.pending()) return;
    out_.close();
    resuming_.abandon();
}

void Watchpoints::write(double t, const protocol::F64Array& displacement) {
    for (const Point& p : points_) {
        auto d = protocol::interpolate(p.where, displacement);
        // The name goes in as it is, not through a fixed buffer: one cut short there lost its line's end, and
        // the row ran into the next (a 240-character name, a review, 2026-11-27).
        char time[32], numbers[128];
        std::snprintf(time, sizeof time, "%.12g,", t);
        std::snprintf(numbers, sizeof numbers, ",%.12g,%.12g,%.12g,%.12g\n", p.x + d[0], p.y + d[1], d[0], d[1]);
        out_ << time << p.name << numbers;
    }
}

void Watchpoints::flush() {
    if (!out_.is_open()) return;  // an abandoned resume's rows, removed
    out_.flush();
    if (!out_)
        throw std::runtime_error("cannot write " + (resuming_.pending() ? resuming_.path() : file_).string() +
                                 " (is the disk full?)");
}

}  // namespace sphfsi::coordinator
