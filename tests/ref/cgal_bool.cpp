/* cgal_bool.cpp — the CGAL reference of the 3D pipeline: Boolean operations on closed solids.
 *
 * Usage: cgal_bool [--op union|intersection|difference|xor|none] [--fold tree|linear]
 *                  [--groups] [--time] [--out RESULT.off] FILE...
 *
 * Each FILE (.off or .obj, by extension; with --groups each "g"/"o" group of an OBJ is a solid
 * of its own, as in the LAR.jl arrangement outputs whose groups are 3-cells) is read as a polygon
 * soup of doubles (the same doubles cellar reads: coordinates are parsed with strtod, never as
 * exact decimals), turned into a CGAL::Surface_mesh with the Epeck kernel, its faces
 * triangulated (a quad that is planar only up to rounding is split along one diagonal), and
 * checked: closed, no self-intersection, bounding a volume (reoriented when inward).  Then the
 * operation is folded over the inputs with the PMP corefinement functions:
 *   union         A1 ∪ A2 ∪ ... ∪ An
 *   intersection  A1 ∩ A2 ∩ ... ∩ An
 *   difference    A1 − (A2 ∪ ... ∪ An)      (the first minus all the rest)
 *   xor           A1 ⊕ A2 ⊕ ... ⊕ An: the points in an odd number of inputs.  (R ∪ A) − (R ∩ A)
 *                 is not a 2-manifold as soon as two boundaries cross (for two overlapping cubes,
 *                 A − B and B − A touch along edges), so the result is kept as a list of
 *                 interior-disjoint pieces: R ⊕ A = {P − A : P in R} + {A − all P in R}
 *   none          no Boolean operation: only the inputs are read, checked and measured
 * --fold tree (default) combines the operands pairwise (a balanced tree: every operation is
 * associative), --fold linear left to right, R = R op Ai (slower: R grows at every step).
 * One JSON line is printed (also --op none, without the result's fields):
 *   {"op": "union", "kernel": "epeck", "inputs": n, "input_volumes": [v1, ...], "fold": "tree",
 *    "volume": V, "filled_volume": W, "area": A, "faces": F, "vertices": N, "components": K,
 *    "cavities": H, "closed": true, "ms": T}
 * volume: of the result (17 significant digits).  filled_volume: inside its outer shells, that
 * is with its cavities filled: a union of solids can enclose a void that lies in none of them
 * (4 random cubes can), which is a bounded cell of the arrangement, so the arrangement's bounded
 * cells add up to the union's filled_volume, not to its volume.  area: of its boundary (it
 * bounds how much snapping the vertices to a grid of step h may change the volume: by about
 * h * area).  faces, vertices: its triangles and vertices; components: the connected components
 * of its boundary; cavities: those that are walls of voids (odd nesting level).  For xor, all
 * are summed over its pieces, and "pieces" says how many.  closed: CGAL::is_closed of the
 * result; ms: wall time of the Boolean part only (not reading, checking, triangulating or
 * measuring).  --op none prints "volume_sum" (of the inputs) instead of the result's fields.
 * --out writes the result as OFF (17 digits); --time prints the time of every step on stderr.
 *
 * Volumes are the divergence-theorem sum over the triangles, evaluated in double (Neumaier
 * summation, about the bounding box centre) on the vertices rounded to double: the result is
 * exact (Epeck), only its measure is rounded, to about 1e-15 relative for these inputs.  (An
 * exact rational sum is no option: the denominators of the constructed points make it explode.)
 *
 * Kernel: Epeck (exact constructions), the robust choice for chained corefinements.  Building
 * with -DCGAL_BOOL_EPICK gives the same program on Epick (exact predicates, double
 * constructions), for measurement only: every constructed point is rounded, so a chained result
 * may self-intersect (it then checks every step, and fails) and nothing guarantees the result.
 * Measured on bench/gen3d.py inputs (union, tree fold, 2 CPUs): Epick worked on all of them,
 * with the same volumes to 2e-16, in 0.65 (100 cubes: 1.3 s), 0.7 (1000 cubes: 21 s) and 1.05
 * (grid 10: 4.9 s) of Epeck's time: not worth the doubt.
 *
 * Exit status: 0 on success; 1 on a usage error or an unreadable / invalid input (not closed,
 * self-intersecting, not bounding a volume); 2 when CGAL fails (a corefinement that cannot
 * produce a manifold result, or throws).  Messages on stderr.
 */
#ifdef CGAL_BOOL_EPICK
#include <CGAL/Exact_predicates_inexact_constructions_kernel.h>
typedef CGAL::Exact_predicates_inexact_constructions_kernel Kernel;
#define KERNEL_NAME "epick"
#else
#include <CGAL/Exact_predicates_exact_constructions_kernel.h>
typedef CGAL::Exact_predicates_exact_constructions_kernel Kernel;
#define KERNEL_NAME "epeck"
#endif
#include <CGAL/Exact_predicates_inexact_constructions_kernel.h>
#include <CGAL/IO/OFF.h>
#include <CGAL/Polygon_mesh_processing/connected_components.h>
#include <CGAL/Polygon_mesh_processing/corefinement.h>
#include <CGAL/Polygon_mesh_processing/orient_polygon_soup.h>
#include <CGAL/Polygon_mesh_processing/orientation.h>
#include <CGAL/Polygon_mesh_processing/polygon_soup_to_polygon_mesh.h>
#include <CGAL/Polygon_mesh_processing/repair_polygon_soup.h>
#include <CGAL/Polygon_mesh_processing/self_intersections.h>
#include <CGAL/Polygon_mesh_processing/triangulate_faces.h>
#include <CGAL/Surface_mesh.h>

#include <array>
#include <chrono>
#include <cmath>
#include <cstdio>
#include <cstdlib>
#include <cstring>
#include <exception>
#include <functional>
#include <fstream>
#include <sstream>
#include <string>
#include <utility>
#include <vector>

namespace PMP = CGAL::Polygon_mesh_processing;
typedef Kernel::Point_3 Point;
typedef CGAL::Surface_mesh<Point> Mesh;
typedef std::array<double, 3> P3;

#include "cgal_soup.hpp"

static bool g_time = false; /* --time: a line on stderr per step */

static void step(const char *what, double ms)
{
    if (g_time) std::fprintf(stderr, "cgal_bool: %-40s %10.2f ms\n", what, ms);
}

/* ---- meshes ------------------------------------------------------------------------------- */

static double to_d(const Kernel::FT &x)
{
#ifdef CGAL_BOOL_EPICK
    return x;
#else
    /* The lazy approximation is an interval; refine to the exact value when it is wide. */
    std::pair<double, double> i = CGAL::to_interval(x);
    if (i.first == i.second) return i.first;
    if (i.second - i.first > 1e-15 * std::fabs(i.first)) CGAL::exact(x);
    return CGAL::to_double(x);
#endif
}

/* What is printed of a closed, outward triangle mesh (see the file comment). */
struct Measure {
    double volume = 0, area = 0;
    double filled = 0;     /* the volume inside the outer shells: cavities filled */
    size_t components = 0; /* connected components of the surface */
    size_t cavities = 0;   /* components at an odd nesting level: the walls of voids */
};

/* Neumaier's compensated sum. */
struct Sum {
    double s = 0, c = 0;
    void add(double x)
    {
        double t = s + x;
        c += std::fabs(s) >= std::fabs(x) ? (s - t) + x : (x - t) + s;
        s = t;
    }
    double value() const { return s + c; }
};

/* nested: also the components and their nesting (the ray tests cost a little: not for the
 * inputs, which bound a volume and are measured whole). */
static Measure measure(Mesh &m, bool nested)
{
    Measure r;
    if (m.number_of_faces() == 0) return r;
    std::vector<P3> p(m.number_of_vertices());
    double lo[3] = {HUGE_VAL, HUGE_VAL, HUGE_VAL}, hi[3] = {-HUGE_VAL, -HUGE_VAL, -HUGE_VAL};
    for (Mesh::Vertex_index v : m.vertices()) {
        const Point &q = m.point(v);
        P3 d = {to_d(q.x()), to_d(q.y()), to_d(q.z())};
        for (int k = 0; k < 3; k++) {
            lo[k] = std::min(lo[k], d[k]);
            hi[k] = std::max(hi[k], d[k]);
        }
        p[v.idx()] = d;
    }
    double c[3];
    for (int k = 0; k < 3; k++) c[k] = 0.5 * (lo[k] + hi[k]);

    auto fcc = m.add_property_map<Mesh::Face_index, std::size_t>("f:cgal_bool_cc", 0).first;
    std::vector<std::size_t> level(1, 0);
    if (nested) {
        auto fvol = m.add_property_map<Mesh::Face_index, std::size_t>("f:cgal_bool_vol", 0).first;
        level.clear();
        PMP::volume_connected_components(
            m, fvol,
            CGAL::parameters::face_connected_component_map(fcc).nesting_levels(std::ref(level)));
        m.remove_property_map(fvol);
    }
    std::vector<Sum> cc(level.size());
    Sum all, area;
    for (Mesh::Face_index f : m.faces()) {
        P3 t[3];
        int n = 0;
        for (Mesh::Vertex_index v : CGAL::vertices_around_face(m.halfedge(f), m)) {
            if (n == 3) break;
            const P3 &q = p[v.idx()];
            t[n++] = P3{q[0] - c[0], q[1] - c[1], q[2] - c[2]};
        }
        double x = t[0][0] * (t[1][1] * t[2][2] - t[1][2] * t[2][1]) -
                   t[0][1] * (t[1][0] * t[2][2] - t[1][2] * t[2][0]) +
                   t[0][2] * (t[1][0] * t[2][1] - t[1][1] * t[2][0]);
        all.add(x);
        cc.at(fcc[f]).add(x);
        double u[3], w[3];
        for (int k = 0; k < 3; k++) {
            u[k] = t[1][k] - t[0][k];
            w[k] = t[2][k] - t[0][k];
        }
        area.add(0.5 * std::sqrt(std::pow(u[1] * w[2] - u[2] * w[1], 2) +
                                 std::pow(u[2] * w[0] - u[0] * w[2], 2) +
                                 std::pow(u[0] * w[1] - u[1] * w[0], 2)));
    }
    m.remove_property_map(fcc);
    r.volume = all.value() / 6;
    r.area = area.value();
    r.components = level.size();
    Sum filled;
    for (size_t i = 0; i < level.size(); i++) {
        if (level[i] == 0) filled.add(cc[i].value());
        if (level[i] % 2) r.cavities++;
    }
    r.filled = filled.value() / 6;
    return r;
}

/* ---- the Boolean fold ---------------------------------------------------------------------- */

enum Op { OP_UNION, OP_INTERSECTION, OP_DIFFERENCE, OP_XOR, OP_NONE };
static const char *const op_names[] = {"union", "intersection", "difference", "xor", "none"};

struct Cgal_failure : std::exception {
    std::string what_;
    explicit Cgal_failure(std::string w) : what_(std::move(w)) {}
    const char *what() const noexcept override { return what_.c_str(); }
};

/* A result: one mesh, or for xor a list of meshes with disjoint interiors (the points in an odd
 * number of inputs make a non-manifold solid as soon as two boundaries cross: two overlapping
 * cubes' A − B and B − A touch along edges; a Surface_mesh cannot hold that, a list can). */
typedef std::vector<Mesh> Pieces;

/* a op b into a fresh mesh (a and b are corefined in place: same solids, more triangles). */
static Mesh combine(Op op, Mesh &a, Mesh &b)
{
    Mesh r;
    bool ok = false;
#ifdef CGAL_BOOL_EPICK
    /* Rounded constructions may make a result self-intersect: find it at the next step. */
    auto np = CGAL::parameters::throw_on_self_intersection(true);
#else
    /* The inputs were checked, and exact results do not self-intersect: the check
     * (throw_on_self_intersection) would only cost time, 8 times the rest on 100 cubes. */
    auto np = CGAL::parameters::default_values();
#endif
    switch (op) {
    case OP_UNION:
        ok = PMP::corefine_and_compute_union(a, b, r, np);
        break;
    case OP_INTERSECTION:
        ok = PMP::corefine_and_compute_intersection(a, b, r, np);
        break;
    case OP_DIFFERENCE:
        ok = PMP::corefine_and_compute_difference(a, b, r, np);
        break;
    case OP_XOR:
    case OP_NONE:
        break;
    }
    if (!ok)
        throw Cgal_failure(std::string("corefine_and_compute_") + op_names[op] +
                           " could not make a manifold result");
#ifndef CGAL_BOOL_EPICK
    /* Each constructed point is a lazy DAG reaching back to the inputs; evaluating it now and
     * keeping only the exact value spares the next steps the re-evaluation (25% faster on 100
     * cubes, same memory). */
    for (Mesh::Vertex_index v : r.vertices()) r.point(v) = Point(CGAL::exact(r.point(v)));
#endif
    return r;
}

/* a op b; for xor: every piece of a minus all of b's, and every piece of b minus all of a's
 * (the pieces of a result are interior-disjoint, so this is the symmetric difference). */
static Pieces combine(Op op, Pieces &a, Pieces &b)
{
    if (op != OP_XOR) return Pieces{combine(op, a.at(0), b.at(0))};
    Pieces out;
    for (int side = 0; side < 2; side++) {
        Pieces &from = side ? b : a, &minus = side ? a : b;
        for (Mesh &p : from) {
            Mesh r = p;
            for (size_t i = 0; i < minus.size() && r.number_of_faces(); i++)
                r = combine(OP_DIFFERENCE, r, minus[i]);
            if (r.number_of_faces()) out.push_back(std::move(r));
        }
    }
    return out;
}

static size_t faces(const Pieces &ps)
{
    size_t n = 0;
    for (const Mesh &m : ps) n += m.number_of_faces();
    return n;
}

/* Folds op over ms[lo, hi) (consumed): pairwise when tree, else left to right. */
static Pieces fold(Op op, std::vector<Pieces> &ms, size_t lo, size_t hi, bool tree, size_t &steps)
{
    if (hi - lo == 1) return std::move(ms[lo]);
    Pieces r;
    if (!tree) {
        r = std::move(ms[lo]);
        for (size_t i = lo + 1; i < hi; i++) {
            double t0 = now_ms();
            r = combine(op, r, ms[i]);
            ms[i].clear();
            if (g_time) {
                char what[64];
                std::snprintf(what, sizeof what, "step %zu (%zu faces)", ++steps, faces(r));
                step(what, now_ms() - t0);
            }
        }
        return r;
    }
    size_t mid = lo + (hi - lo) / 2;
    Pieces a = fold(op, ms, lo, mid, tree, steps);
    Pieces b = fold(op, ms, mid, hi, tree, steps);
    double t0 = now_ms();
    r = combine(op, a, b);
    if (g_time) {
        char what[64];
        std::snprintf(what, sizeof what, "step %zu (%zu faces)", ++steps, faces(r));
        step(what, now_ms() - t0);
    }
    return r;
}

static int usage()
{
    std::fprintf(
        stderr,
        "usage: cgal_bool [--op union|intersection|difference|xor|none] "
        "[--fold tree|linear] [--groups] [--time] [--out RESULT.off] FILE.off|FILE.obj...\n");
    return 1;
}

int main(int argc, char **argv)
{
    Op op = OP_UNION;
    bool tree = true, groups = false;
    const char *outpath = nullptr;
    std::vector<std::string> files;
    for (int i = 1; i < argc; i++) {
        std::string a = argv[i];
        if (a == "--op" && i + 1 < argc) {
            std::string v = argv[++i];
            int k = 0;
            while (k < 5 && v != op_names[k]) k++;
            if (k == 5) return usage();
            op = (Op)k;
        } else if (a == "--fold" && i + 1 < argc) {
            std::string v = argv[++i];
            if (v != "tree" && v != "linear") return usage();
            tree = v == "tree";
        } else if (a == "--out" && i + 1 < argc) {
            outpath = argv[++i];
        } else if (a == "--groups") {
            groups = true;
        } else if (a == "--time") {
            g_time = true;
        } else if (a == "--help" || a == "-h") {
            usage();
            return 0;
        } else if (a.size() > 1 && a[0] == '-') {
            return usage();
        } else {
            files.push_back(a);
        }
    }
    if (files.empty()) return usage();

    double t0 = now_ms();
    std::vector<Soup> soups;
    for (const std::string &f : files) {
        std::string why;
        bool ok;
        if (ends_with(f, ".off"))
            ok = read_off(f, soups, why);
        else if (ends_with(f, ".obj"))
            ok = read_obj(f, groups, soups, why);
        else {
            ok = false;
            why = "expected a .off or .obj file";
        }
        if (!ok) {
            std::fprintf(stderr, "cgal_bool: %s: %s\n", f.c_str(), why.c_str());
            return 1;
        }
    }
    step("read", now_ms() - t0);

    t0 = now_ms();
    std::vector<Pieces> meshes(soups.size(), Pieces(1));
    std::vector<double> vols(soups.size());
    try {
        for (size_t i = 0; i < soups.size(); i++) {
            std::string why;
            if (!make_mesh(soups[i], meshes[i][0], why)) {
                std::fprintf(stderr, "cgal_bool: %s: %s\n", soups[i].label.c_str(), why.c_str());
                return 1;
            }
            vols[i] = measure(meshes[i][0], false).volume;
        }
    } catch (const std::exception &e) {
        std::fprintf(stderr, "cgal_bool: checking the inputs: %s\n", e.what());
        return 2;
    }
    soups.clear();
    step("meshes, checks, input volumes", now_ms() - t0);

    double vsum;
    std::string js = result_head(op_names[op], KERNEL_NAME, meshes.size(), vols, &vsum);
    if (op == OP_NONE) {
        std::printf("%s, \"volume_sum\": %s}\n", js.c_str(), num(vsum).c_str());
        return 0;
    }

    Pieces r;
    double ms;
    try {
        size_t steps = 0;
        t0 = now_ms();
        if (op == OP_DIFFERENCE && meshes.size() > 2) {
            Pieces rest = fold(OP_UNION, meshes, 1, meshes.size(), tree, steps);
            r = combine(OP_DIFFERENCE, meshes[0], rest);
        } else {
            r = fold(op, meshes, 0, meshes.size(), tree, steps);
        }
        ms = now_ms() - t0;
    } catch (const std::exception &e) {
        std::fprintf(stderr, "cgal_bool: %s failed: %s\n", op_names[op], e.what());
        return 2;
    }
    step("boolean (total)", ms);

    t0 = now_ms();
    Measure all;
    size_t nf = 0, nv = 0;
    bool closed = true;
    for (Mesh &m : r) {
        Measure one = measure(m, true);
        all.volume += one.volume;
        all.area += one.area;
        all.filled += one.filled;
        all.components += one.components;
        all.cavities += one.cavities;
        nf += m.number_of_faces();
        nv += m.number_of_vertices();
        closed = closed && CGAL::is_closed(m);
    }
    step("result volume, components", now_ms() - t0);
    char tail[256];
    std::snprintf(tail, sizeof tail,
                  ", \"faces\": %zu, \"vertices\": %zu, \"components\": %zu, \"cavities\": %zu, "
                  "\"closed\": %s, \"ms\": %.3f",
                  nf, nv, all.components, all.cavities, closed ? "true" : "false", ms);
    std::printf("%s, \"fold\": \"%s\", \"volume\": %s, \"filled_volume\": %s, \"area\": %s%s",
                js.c_str(), tree ? "tree" : "linear", num(all.volume).c_str(),
                num(all.filled).c_str(), num(all.area).c_str(), tail);
    if (op == OP_XOR) std::printf(", \"pieces\": %zu", r.size());
    std::printf("}\n");
    if (outpath) {
        Mesh all;
        for (const Mesh &m : r) all += m;
        std::ofstream out(outpath);
        if (!out || !CGAL::IO::write_OFF(out, all, CGAL::parameters::stream_precision(17))) {
            std::fprintf(stderr, "cgal_bool: cannot write %s\n", outpath);
            return 1;
        }
    }
    return 0;
}
