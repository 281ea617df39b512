#pragma once
// The kernel choices a scene can name, and their support radius in units of h. Kept free of the kernel
// code itself so the scene schema (linked by the coordinator) stays light.
#include <string_view>

namespace sphfsi::fluid {

enum class KernelChoice { Mueller, Poly6, Spiky, CubicSpline, Wendland, Gaussian };

// "mueller" is the thesis's set: poly6 for densities, spiky for pressure gradients (and Mueller's
// viscosity kernel when the viscosity model is "mueller").
inline constexpr std::string_view kernel_choice_names[] = {"mueller", "poly6", "spiky", "cubic_spline", "wendland", "gaussian"};

inline double kernel_support_factor(std::string_view name) { return name == "gaussian" ? 3.0 : 2.0; }

}  // namespace sphfsi::fluid
