#pragma once
// The cross-section of a moving solid (a coupled structure's interface mesh, or the lifted gate) as the
// fluid's failure check sees it: a fluid centre deep inside it has gone through the solid, as one beyond a
// tank wall's outer face has gone through that wall.
//
// The rule is the static obstacles' (Simulation2D::through_obstacle), stated for any union of quadrilateral
// cells. A centre inside the union is still "at" a face f the water can touch when its depth d below f is
// at most allowed(f) = min(L, max((w - dp)/2, dp/2)), where L is how deep the wall layers reach (the tank's
// wall thickness, a kernel support) and w the section's thickness through the centre across f (from f, along
// the line from f's nearest point through the centre, to where that line leaves the union). It is lost when
// it is at no face: deeper than L below every face, or, across a section thinner than 2 L + dp, within dp/2
// of the middle and more than dp/2 past the face (a step moves a particle a small fraction of a spacing, so
// one passing through lands in that band; without the repulsive force centres sit up to 0.43 dp past a
// surface). A section no thicker than dp has no such band (crossed_middle, below, covers one meshed a cell
// thick). For a box inside the tank this is through_obstacle (a review compared 160,000 points in 400 boxes
// of 1 - 25 cells); unlike it, the section ends at the tank's wall surfaces (a centre squeezing under a gate
// standing on the floor, through the floor's own layers, is caught only below them, by the floor's check).
//
// Why these choices (reviews of a first version, reverted, and of this one found each of them wrong there):
// - Faces are the edges no two cells share, found by the vertices' reference positions, so a mesh of several
//   cells through the thickness, or one whose cells do not share vertex indices, has no inner faces. Where
//   cells overlap (the members of a frame meeting at a joint, each with its own cells), a face is a surface
//   only where the union ends just beyond it, and the thickness is measured to where the union ends.
// - Depth is measured to every face of the whole union, not to the faces of the cell holding the centre:
//   with elements shorter than dp, a centre just past a member's end lies in a cell with no end face.
// - A face counts only where the centre lies over it (its projection falls on the segment), or where its
//   nearest point is a corner: measured obliquely from a far segment, a thin section looks thick.
// - Water touches a face only inside the tank's interior, judged at the point the depth is measured from
//   (a plate's end set into a side wall and a member's foot on the floor are not the water's): one element
//   may run from inside a wall out into the water.
// - Cells and faces are binned on a grid a quarter of 2 L + dp wide, rebuilt at every placement: a particle
//   tests the cells of its own bin, and only a centre inside the section looks at faces, within 2 L + dp.
//
// A part no thicker than dp has no depth band, so the rule above cannot see water through it. As for the
// static obstacles (Simulation2D::across_obstacle_middle), the step's path shows it: a cell whose two
// opposite edges are both faces spans the part's thickness, and the line joining the midpoints of its other
// two edges is the part's middle there; a step whose path (x - dt v at t - dt to x at t, against the middle
// where it was at each of those times) crosses it has gone from one face past the middle, where the part's
// own solid particles sit. Within dp/2 of an end of the line that is a face the water can touch (a free
// end, or an end drawn to a point) it is not counted: water turning round the end crosses there. A part
// meshed with several cells through its thickness has no such cell and is left to the depth rule alone,
// which misses water through it when it is no thicker than dp (no mesh we publish is: docs/coupling.md).
#include <array>
#include <cstdint>
#include <functional>
#include <string>
#include <vector>

#include "sphfsi/fluid/vec.hpp"

namespace sphfsi::fluid {

class SolidSection {
public:
    using Quad = std::array<std::int32_t, 4>;                                 // vertex indices, either turning
    using Vertices = std::function<void(double t, std::vector<Vec2>& out)>;  // the vertices' places at time t
    using Touchable = std::function<bool(const Vec2& p)>;  // can water touch a face at its point p?

    SolidSection() = default;
    // `name` names the solid in failure messages ("the structure", "the gate"); `reference`: the vertices'
    // reference positions (faces are found from them); `layers`: L above; `dp`: the particle spacing.
    SolidSection(std::string name, std::vector<Quad> cells, const std::vector<Vec2>& reference, Vertices vertices,
                 Touchable touchable, double layers, double dp);

    bool on() const { return static_cast<bool>(vertices_); }
    const std::string& name() const { return name_; }
    // Moves the section to time t; lost() then answers for positions at that time, and crossed_middle() for
    // a step from t - dt to t.
    void place(double t, double dt = 0.0);
    // Whether a fluid centre at x is deeper inside the section than the rule above allows.
    bool lost(const Vec2& x) const;
    // Whether the step from `from` (at t - dt) to `to` (at t) crossed a thin part's middle (above).
    bool crossed_middle(const Vec2& from, const Vec2& to) const;
    // Whether x is inside the section further than `tol` from every face the water can touch (the
    // validation's count of wall crossings, Simulation2D::wall_crossings).
    bool past_surface(const Vec2& x, double tol) const;

private:
    struct Face {
        Vec2 a, b;
    };
    // Items binned on the grid, as offsets into one list (the bins of a cell's or face's bounding box).
    struct Bins {
        std::vector<std::uint32_t> start, items;
    };
    bool inside(const Vec2& x) const;
    bool surface_at(const Vec2& foot, const Vec2& inward) const;  // the union ends at foot, water can touch it
    bool surface_within(const Vec2& x, double tol) const;
    double reach() const { return 2.0 * layers_ + dp_; }  // the farthest a face can matter: 2 L + dp
    const std::vector<std::uint32_t>& faces_near(const Vec2& x, int bins) const;
    void gather(const Bins& bins, std::array<int, 2> b0, std::array<int, 2> b1, std::vector<std::uint32_t>& out) const;
    bool at_a_face(const Vec2& x, const Vec2& foot, double depth, const std::vector<std::uint32_t>& near) const;
    std::array<int, 2> bin_of(const Vec2& x) const;
    template <class Box>
    void fill(Bins& bins, std::size_t n, const Box& box_of);

    std::string name_;
    std::vector<Quad> cells_;
    std::vector<std::array<std::int32_t, 2>> faces_;  // vertex index pairs of the edges no two cells share
    // Per cell, bit k: its edge k (vertex k to k + 1) is a face, or drawn to a point (a pointed end, an end
    // for crossed_middle though not a face). A cell with edges k and k + 2 so marked spans the thickness
    // across them (its middle line joins the midpoints of edges k + 1 and k + 3).
    std::vector<std::uint8_t> face_edges_;
    bool any_middle_ = false;  // some cell spans the thickness
    Vertices vertices_;
    Touchable touchable_;
    double layers_ = 0.0, dp_ = 0.0;

    // At the placed time:
    std::vector<Vec2> at_, before_;  // the vertices at t and at t - dt
    std::vector<Face> placed_faces_;
    Vec2 lo_{}, hi_{};  // bounding box of the vertices
    double bin_ = 1.0;
    int nx_ = 0, ny_ = 0, reach_ = 1;  // reach_: bins on each side that cover 2 L + dp
    Bins cell_bins_, face_bins_;
};

}  // namespace sphfsi::fluid
