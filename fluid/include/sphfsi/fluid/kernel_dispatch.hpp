#pragma once
// Turns the scene's kernel choice into concrete kernel types once per pass, so the hot loops are compiled
// for each kernel with the kernel inlined (no virtual call or std::function per pair).
#include "sphfsi/fluid/kernel_names.hpp"
#include "sphfsi/fluid/kernels.hpp"

namespace sphfsi::fluid {

// Calls f(density_kernel, gradient_kernel). For the thesis's "mueller" set these differ (poly6, spiky).
template <int Dim, class F>
decltype(auto) with_kernels(KernelChoice choice, double h, F&& f) {
    switch (choice) {
        case KernelChoice::Mueller: return f(Poly6Kernel<Dim>(h), SpikyKernel<Dim>(h));
        case KernelChoice::Poly6: { const Poly6Kernel<Dim> k(h); return f(k, k); }
        case KernelChoice::Spiky: { const SpikyKernel<Dim> k(h); return f(k, k); }
        case KernelChoice::CubicSpline: { const CubicSplineKernel<Dim> k(h); return f(k, k); }
        case KernelChoice::Gaussian: { const GaussianKernel<Dim> k(h); return f(k, k); }
        case KernelChoice::Wendland: break;
    }
    const WendlandC2Kernel<Dim> k(h);
    return f(k, k);
}

inline double support_radius(KernelChoice choice, double h) {
    return (choice == KernelChoice::Gaussian ? GaussianKernel<2>::support_factor : 2.0) * h;
}

}  // namespace sphfsi::fluid
