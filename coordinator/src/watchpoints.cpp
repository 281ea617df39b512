#include "sphfsi/coordinator/watchpoints.hpp"

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <sstream>

namespace sphfsi::coordinator {

Watchpoints::Watchpoints(const std::filesystem::path& file, const Value& scene, const protocol::InterfaceMesh& mesh,
                         bool append, double resume_t) {
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
    std::string kept;
    if (append && std::filesystem::exists(file)) {  // keep the rows up to the checkpoint
        std::ifstream in(file);
        std::string line;
        std::getline(in, line);
        while (std::getline(in, line))
            if (std::stod(line.substr(0, line.find(','))) <= resume_t * (1 + 1e-12)) kept += line + "\n";
    }
    out_.open(file, std::ios::trunc);
    out_ << "time,name,x,y,dx,dy\n" << kept;
}

void Watchpoints::write(double t, const protocol::F64Array& displacement) {
    for (const Point& p : points_) {
        auto d = protocol::interpolate(p.where, displacement);
        char line[256];
        std::snprintf(line, sizeof line, "%.12g,%s,%.12g,%.12g,%.12g,%.12g\n", t, p.name.c_str(), p.x + d[0], p.y + d[1], d[0], d[1]);
        out_ << line;
    }
}

}  // namespace sphfsi::coordinator
