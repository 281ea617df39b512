#include "sphfsi/coordinator/scene_warnings.hpp"

namespace sphfsi::coordinator {
namespace {

const std::string* string_at(const Value& tree, const char* path) {
    const Value* v = find_path(tree, path);
    return v && v->is_string() ? &v->as_string() : nullptr;
}

bool is(const Value& tree, const char* path, const char* value) {
    const std::string* s = string_at(tree, path);
    return s && *s == value;
}

}  // namespace

std::vector<std::string> scene_warnings(const Scene& scene) {
    std::vector<std::string> out;
    const Value& t = scene.tree;
    // A warning, not an error: heavier structures are fine with any integrator (docs/validation.md). About
    // the built-in structure only: a foreign one's [structure] keys are its own.
    if (scene.has("fluid") && scene.has("structure") && is(t, "coupling.structure_steps", "window") &&
        !scene.custom_program("structure") && !is(t, "structure.time.integrator", "backward_euler"))
        out.push_back("coupling.structure_steps = \"window\" is meant with structure.time.integrator = "
                      "\"backward_euler\", whose step acceleration is the window's mean; one generalized-alpha step per "
                      "window failed from mass ratio 0.001 on the added-mass plate (docs/coupling.md)");
    // The thesis's kernel pair is allowed (issue 4 asks for it), but with summed densities (which PCISPH
    // requires) its acoustic modes about 2.3 dp long grow at rest once the support reaches the second ring of
    // neighbours: the von Neumann analysis of docs/validation/vonneumann.py, tested in
    // tests/fluid/test_kernel_pair_stability.cpp, and a tank at rest that boils (docs/validation.md).
    if (scene.has("fluid") && !scene.custom_program("fluid") && is(t, "fluid.kernel", "mueller")) {
        const bool summed = is(t, "fluid.density.method", "summation") || is(t, "fluid.density.method", "shepard");
        const Value* h = find_path(t, "fluid.h_over_dp");
        if (summed && h && h->is_number() && h->as_double() > 1.0)
            out.push_back("fluid.kernel = \"mueller\" with summed densities (poly6 sums, spiky pressure gradients) is "
                          "unstable at rest for h_over_dp > 1.0: acoustic modes about 2.3 dp long grow whatever the step "
                          "(docs/validation.md, \"The thesis's kernel pair at rest\"); with density.method = "
                          "\"continuity\" (spiky gradients alone) or another kernel they do not");
    }
    return out;
}

}  // namespace sphfsi::coordinator
