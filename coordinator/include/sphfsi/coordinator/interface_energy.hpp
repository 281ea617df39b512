#pragma once
// Energy balance across the coupling interface. Over a window the structure moved the interface by du_s
// under the force F_s it was given (constant over the window: the fluid's window mean), so that force did
// work F_s . du_s on it; the fluid gave up F_f . du_f, with F_f the force it returned for the window and du_f
// how far it moved the interface itself (the predicted or iterated displacement it was given). The serial
// and implicit schemes give the structure the fluid's force of the same window (F_s = F_f); the parallel
// scheme gives it the previous window's. A partitioned scheme that lets the two sides differ creates (or
// destroys) F_s . du_s - F_f . du_f at the interface: the energy an explicit scheme feeds an added-mass
// instability with (Piperno & Farhat 2001). A converged implicit window has du_s = du_f to its tolerance.
// Recorded per window (docs/record.md); in 2D the forces are per unit width, so these are J/m.
#include "sphfsi/protocol/arrays.hpp"

namespace sphfsi::coordinator {

struct InterfaceWork {
    double on_structure = 0.0;  // F_s . du_s
    double created = 0.0;       // F_s . du_s - F_f . du_f
    std::size_t most_created_at = 0;  // the vertex that created the most in the window
};

inline InterfaceWork interface_work(const protocol::F64Array& structure_force, const protocol::F64Array& fluid_force,
                                    const protocol::F64Array& structure_start, const protocol::F64Array& structure_end,
                                    const protocol::F64Array& fluid_start, const protocol::F64Array& fluid_end) {
    InterfaceWork w;
    double most = 0.0;
    const std::size_t dim = fluid_force.shape.size() == 2 ? fluid_force.shape[1] : 1;
    for (std::size_t v = 0; dim > 0 && v < fluid_force.values.size() / dim; ++v) {
        double created = 0.0;
        for (std::size_t i = v * dim; i < (v + 1) * dim; ++i) {
            const double on_structure = structure_force.values[i] * (structure_end.values[i] - structure_start.values[i]);
            const double from_fluid = fluid_force.values[i] * (fluid_end.values[i] - fluid_start.values[i]);
            w.on_structure += on_structure;
            created += on_structure - from_fluid;
        }
        w.created += created;
        if (v == 0 || created > most) most = created, w.most_created_at = v;
    }
    return w;
}

}  // namespace sphfsi::coordinator
