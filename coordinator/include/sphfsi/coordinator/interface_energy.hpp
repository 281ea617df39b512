#pragma once
// Energy balance across the coupling interface. Over a window the fluid's interface force F (constant over
// the window: the window's mean) does work F . du_s on the structure, which moved by du_s, and the fluid
// gives up F . du_f, with du_f how far it moved the interface itself (the predicted or iterated displacement
// it was given). A partitioned scheme that lets the two differ creates (or destroys) the difference,
// F . (du_s - du_f), at the interface: the energy an explicit scheme feeds an added-mass instability with
// (Piperno & Farhat 2001). A converged implicit window has du_s = du_f to its tolerance. Recorded per
// window (docs/record.md); in 2D the forces are per unit width, so these are J/m.
#include "sphfsi/protocol/arrays.hpp"

namespace sphfsi::coordinator {

struct InterfaceWork {
    double on_structure = 0.0;  // F . du_s
    double created = 0.0;       // F . (du_s - du_f)
    std::size_t most_created_at = 0;  // the vertex that created the most in the window
};

inline InterfaceWork interface_work(const protocol::F64Array& force, const protocol::F64Array& structure_start,
                                    const protocol::F64Array& structure_end, const protocol::F64Array& fluid_start,
                                    const protocol::F64Array& fluid_end) {
    InterfaceWork w;
    double most = 0.0;
    const std::size_t dim = force.shape.size() == 2 ? force.shape[1] : 1;
    for (std::size_t v = 0; dim > 0 && v < force.values.size() / dim; ++v) {
        double created = 0.0;
        for (std::size_t i = v * dim; i < (v + 1) * dim; ++i) {
            const double du_s = structure_end.values[i] - structure_start.values[i];
            const double du_f = fluid_end.values[i] - fluid_start.values[i];
            w.on_structure += force.values[i] * du_s;
            created += force.values[i] * (du_s - du_f);
        }
        w.created += created;
        if (v == 0 || created > most) most = created, w.most_created_at = v;
    }
    return w;
}

}  // namespace sphfsi::coordinator
