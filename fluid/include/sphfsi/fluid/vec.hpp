#pragma once
// A small fixed-size vector for particle positions, velocities and accelerations. Dim is a template
// parameter everywhere in the core so that 3D is one more instantiation, not a rewrite.
#include <array>
#include <cmath>

namespace sphfsi::fluid {

template <int Dim>
struct Vec {
    static_assert(Dim == 2 || Dim == 3, "the SPH core is written for 2 or 3 dimensions");
    std::array<double, Dim> c{};

    constexpr double& operator[](int k) { return c[static_cast<std::size_t>(k)]; }
    constexpr double operator[](int k) const { return c[static_cast<std::size_t>(k)]; }

    constexpr Vec& operator+=(const Vec& o) {
        for (int k = 0; k < Dim; ++k) (*this)[k] += o[k];
        return *this;
    }
    constexpr Vec& operator-=(const Vec& o) {
        for (int k = 0; k < Dim; ++k) (*this)[k] -= o[k];
        return *this;
    }
    constexpr Vec& operator*=(double s) {
        for (int k = 0; k < Dim; ++k) (*this)[k] *= s;
        return *this;
    }
    friend constexpr Vec operator+(Vec a, const Vec& b) { return a += b; }
    friend constexpr Vec operator-(Vec a, const Vec& b) { return a -= b; }
    friend constexpr Vec operator*(Vec a, double s) { return a *= s; }
    friend constexpr Vec operator*(double s, Vec a) { return a *= s; }
    friend constexpr Vec operator-(Vec a) { return a *= -1.0; }
    friend constexpr bool operator==(const Vec&, const Vec&) = default;

    static constexpr Vec zero() { return Vec{}; }
};

template <int Dim>
constexpr double dot(const Vec<Dim>& a, const Vec<Dim>& b) {
    double s = 0.0;
    for (int k = 0; k < Dim; ++k) s += a[k] * b[k];
    return s;
}

template <int Dim>
constexpr double norm2(const Vec<Dim>& a) { return dot(a, a); }

template <int Dim>
inline double norm(const Vec<Dim>& a) { return std::sqrt(norm2(a)); }

template <int Dim>
inline bool all_finite(const Vec<Dim>& a) {
    for (int k = 0; k < Dim; ++k)
        if (!std::isfinite(a[k])) return false;
    return true;
}

using Vec2 = Vec<2>;

}  // namespace sphfsi::fluid
