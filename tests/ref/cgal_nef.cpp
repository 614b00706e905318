/* cgal_nef.cpp — the second CGAL reference of the 3D pipeline: Boolean operations on closed
 * solids with Nef polyhedra, which, unlike the corefinement of cgal_bool, represent every
 * result: two solids touching at a vertex, along an edge or in part of a face, a cavity touching
 * the outer boundary, a lower-dimensional intersection.
 *
 * Usage: cgal_nef [--op union|intersection|difference|contact|none] FILE...
 *
 * Each FILE (.off or .obj, by extension; an OBJ is one solid, its groups ignored) is read as a
 * polygon soup of doubles (the same doubles cellar reads: coordinates are parsed with strtod,
 * never as exact decimals), turned into a CGAL::Surface_mesh with the Epeck kernel, its faces
 * triangulated (a quad that is planar only up to rounding is split along one diagonal, as
 * cgal_bool does), checked (closed, no self-intersection, bounding a volume; reoriented when
 * inward) and converted to a CGAL::Nef_polyhedron_3 on the same kernel.  Then the operation is
 * folded over the inputs, left to right, with the Nef operators (+, *, -), which are exact and
 * total on Epeck:
 *   union         A1 ∪ A2 ∪ ... ∪ An
 *   intersection  A1 ∩ A2 ∩ ... ∩ An
 *   difference    A1 − (A2 ∪ ... ∪ An)      (the first minus all the rest)
 *   contact       ∂A1 ∩ ∂A2 ∩ ... ∩ ∂An: where the boundaries meet; for two solids that touch
 *                 (from outside, or one inside the other), where they touch: a point, segments,
 *                 pieces of faces (its counts below tell which)
 *   none          no Boolean operation: only the inputs are read, checked and measured
 * The Nef operations are those of point sets, not regularized: the intersection of two boxes
 * sharing a face is that face, and A − B leaves A open where B touched it.  Neither changes a
 * volume (a set of dimension < 3 has none), so the result is measured as it is.
 * One JSON line is printed:
 *   {"op": "union", "kernel": "epeck-nef", "inputs": n, "input_volumes": [v1, ...],
 *    "volume": V, "volumes": K, "vertices": NV, "edges": NE, "facets": NF, "ms": T}
 * volume: of the result (17 significant digits); volumes: how many bounded volumes (3-cells of
 * the Nef structure: connected open pieces of the interior) it has, e.g. 2 for the union of two
 * boxes that share only an edge; vertices, edges, facets: how many of the Nef structure's are in
 * the set (marked), e.g. 1, 0, 0 for the contact of two solids touching at a point; ms: wall
 * time of the Boolean part only (not reading, checking, building the Nef polyhedra or
 * measuring).  --op none prints "volume_sum" (of the inputs) instead of the result's fields.
 *
 * The volume.  A Nef polyhedron in 3-space is a selective Nef complex (SNC): volumes (maximal
 * connected open regions of space cut by the 2-skeleton, the first of them the unbounded
 * outside), each marked in or out of the set, bounded by halffacets.  Every facet is two
 * halffacets, one on each side, each incident to the volume on its side; so the boundary of a
 * volume C, with all its shells (outer boundary, cavities, however they touch each other at
 * vertices or edges), is exactly the set of halffacets whose incident volume is C, and the
 * divergence theorem gives
 *   vol(C) = 1/3 ∑_{h incident to C} ∫_h x · n_h dA     (n_h: the unit normal pointing out of C)
 * which holds for any bounded open set whose boundary is a finite union of planar polygons,
 * manifold or not.  A halffacet faces its incident volume: CGAL's own Build_polyhedron writes
 * the twin of each halffacet of a volume's shell, its cycle as it is, as an outward facet of the
 * polyhedron; so the twin's facet cycles run counterclockwise about n_h (the outer cycle; the
 * cycles of holes clockwise).  x · n_h is constant on the plane,
 * and for a cycle p0, p1, ..., pk the fan 1/6 ∑ det(p0, p_i, p_i+1) is 1/3 (q · n_h) times the
 * signed area the cycle encloses, for any q in the plane; summed over the outer cycle and the
 * holes it is 1/3 ∫_h x · n_h dA.  (A vertex alone inside a facet, where another solid's vertex
 * touches it, is a cycle of its own, an SHalfloop: a hole of no area, skipped.)  So
 *   volume = 1/6 ∑_{h: incident volume marked} ∑_{cycles of twin(h)} ∑_i det(p0, p_i, p_i+1).
 * The unbounded volume must be unmarked (it is, for Booleans of bounded solids; else exit 2).
 * A facet with a marked volume on both sides (one that divides the interior) adds its integral
 * once with each orientation: nothing, as it should.  The sum is evaluated exactly, in the
 * rationals of Epeck's exact number type on the exact vertices, and rounded once at the end, so
 * the printed volume is the exact volume of the exact result on the input doubles, to 1 ulp.
 * It is checked (tests/contacts3d.py) against closed forms on boxes, tetrahedra, prisms and
 * turned cubes touching at vertices, edges and faces, from outside and inside a container:
 * manifold and non-manifold results, facets with holes, cavities touching the outer boundary.
 *
 * Exit status: 0 on success; 1 on a usage error or an unreadable / invalid input (not closed,
 * self-intersecting, not bounding a volume); 2 when CGAL fails (throws, or an unbounded result).
 * Messages on stderr.
 */
#include <CGAL/Exact_predicates_exact_constructions_kernel.h>
#include <CGAL/Exact_predicates_inexact_constructions_kernel.h>
#include <CGAL/IO/OFF.h>
#include <CGAL/Nef_polyhedron_3.h>
#include <CGAL/Polygon_mesh_processing/orient_polygon_soup.h>
#include <CGAL/Polygon_mesh_processing/orientation.h>
#include <CGAL/Polygon_mesh_processing/polygon_soup_to_polygon_mesh.h>
#include <CGAL/Polygon_mesh_processing/repair_polygon_soup.h>
#include <CGAL/Polygon_mesh_processing/self_intersections.h>
#include <CGAL/Polygon_mesh_processing/triangulate_faces.h>
#include <CGAL/Surface_mesh.h>

#include <chrono>
#include <cmath>
#include <cstdio>
#include <cstdlib>
#include <cstring>
#include <exception>
#include <fstream>
#include <string>
#include <utility>
#include <vector>

typedef CGAL::Exact_predicates_exact_constructions_kernel Kernel;
#define KERNEL_NAME "epeck-nef"

namespace PMP = CGAL::Polygon_mesh_processing;
typedef Kernel::Point_3 Point;
typedef CGAL::Surface_mesh<Point> Mesh;
typedef CGAL::Nef_polyhedron_3<Kernel> Nef;
typedef CGAL::Epeck_ft Exact; /* the exact rationals under Epeck's lazy numbers */

#include "cgal_soup.hpp"

/* ---- meshes and Nef polyhedra -------------------------------------------------------------- */

struct Cgal_failure : std::exception {
    std::string what_;
    explicit Cgal_failure(std::string w) : what_(std::move(w)) {}
    const char *what() const noexcept override { return what_.c_str(); }
};

/* The volume of a Nef polyhedron and how many bounded volumes it has (see the file comment). */
static double measure(const Nef &n, size_t *cells)
{
    Nef::Volume_const_iterator c = n.volumes_begin();
    if (c != n.volumes_end() && c->mark())
        throw Cgal_failure("the result is unbounded (its outer volume is marked)");
    size_t k = 0;
    for (; c != n.volumes_end(); ++c)
        if (c->mark()) k++;
    if (cells) *cells = k;
    Exact sum = 0;
    std::vector<Exact> p; /* the cycle's points, x y z */
    Nef::Halffacet_const_iterator h;
    for (h = n.halffacets_begin(); h != n.halffacets_end(); ++h) {
        if (!h->incident_volume()->mark()) continue;
        Nef::Halffacet_const_handle f = h->twin(); /* its normal points out of the volume */
        Nef::Halffacet_cycle_const_iterator fc;
        for (fc = f->facet_cycles_begin(); fc != f->facet_cycles_end(); ++fc) {
            /* An SHalfloop cycle is a vertex alone inside the facet (another solid's vertex
             * touching it): a hole of no area. */
            if (fc.is_shalfloop()) continue;
            if (!fc.is_shalfedge()) throw Cgal_failure("a facet cycle of an unknown kind");
            p.clear();
            Nef::SHalfedge_const_handle se(fc);
            Nef::SHalfedge_around_facet_const_circulator e(se), end(e);
            CGAL_For_all(e, end)
            {
                const Point &q = e->source()->center_vertex()->point();
                p.push_back(CGAL::exact(q.x()));
                p.push_back(CGAL::exact(q.y()));
                p.push_back(CGAL::exact(q.z()));
            }
            size_t m = p.size() / 3;
            for (size_t i = 1; i + 1 < m; i++) {
                const Exact *a = &p[0], *b = &p[3 * i], *d = &p[3 * i + 3];
                sum += a[0] * (b[1] * d[2] - b[2] * d[1]) - a[1] * (b[0] * d[2] - b[2] * d[0]) +
                       a[2] * (b[0] * d[1] - b[1] * d[0]);
            }
        }
    }
    sum /= 6;
    return CGAL::to_double(sum);
}

/* ---- the Boolean fold ---------------------------------------------------------------------- */

enum Op { OP_UNION, OP_INTERSECTION, OP_DIFFERENCE, OP_CONTACT, OP_NONE };
static const char *const op_names[] = {"union", "intersection", "difference", "contact", "none"};

/* How many vertices, edges and facets of n are in the set (each edge is two halfedges, each
 * facet two halffacets, with the same mark). */
static void count(const Nef &n, size_t *nv, size_t *ne, size_t *nf)
{
    *nv = *ne = *nf = 0;
    for (Nef::Vertex_const_iterator v = n.vertices_begin(); v != n.vertices_end(); ++v)
        if (v->mark()) ++*nv;
    for (Nef::Halfedge_const_iterator e = n.halfedges_begin(); e != n.halfedges_end(); ++e)
        if (e->mark()) ++*ne;
    for (Nef::Halffacet_const_iterator f = n.halffacets_begin(); f != n.halffacets_end(); ++f)
        if (f->mark()) ++*nf;
    *ne /= 2;
    *nf /= 2;
}

static int usage()
{
    std::fprintf(stderr, "usage: cgal_nef [--op union|intersection|difference|contact|none] "
                         "FILE.off|FILE.obj...\n");
    return 1;
}

int main(int argc, char **argv)
{
    Op op = OP_UNION;
    std::vector<std::string> files;
    for (int i = 1; i < argc; i++) {
        std::string a = argv[i];
        if (a == "--op" && i + 1 < argc) {
            std::string v = argv[++i];
            int k = 0;
            while (k < 5 && v != op_names[k]) k++;
            if (k == 5) return usage();
            op = (Op)k;
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

    std::vector<Soup> soups; /* one per file: an OBJ file is one solid here */
    for (size_t i = 0; i < files.size(); i++) {
        const std::string &f = files[i];
        std::string why;
        bool ok;
        if (ends_with(f, ".off"))
            ok = read_off(f, soups, why);
        else if (ends_with(f, ".obj"))
            ok = read_obj(f, false, soups, why);
        else {
            ok = false;
            why = "expected a .off or .obj file";
        }
        if (!ok) {
            std::fprintf(stderr, "cgal_nef: %s: %s\n", f.c_str(), why.c_str());
            return 1;
        }
    }

    std::vector<Nef> nefs;
    std::vector<double> vols(soups.size());
    try {
        for (size_t i = 0; i < soups.size(); i++) {
            Mesh m;
            std::string why;
            if (!make_mesh(soups[i], m, why)) {
                std::fprintf(stderr, "cgal_nef: %s: %s\n", soups[i].label.c_str(), why.c_str());
                return 1;
            }
            nefs.emplace_back(m);
            if (!nefs.back().is_simple()) {
                std::fprintf(stderr, "cgal_nef: %s: its Nef polyhedron is not a 2-manifold\n",
                             soups[i].label.c_str());
                return 1;
            }
            vols[i] = measure(nefs.back(), nullptr);
        }
    } catch (const std::exception &e) {
        std::fprintf(stderr, "cgal_nef: building the inputs: %s\n", e.what());
        return 2;
    }
    soups.clear();

    double vsum;
    std::string js = result_head(op_names[op], KERNEL_NAME, nefs.size(), vols, &vsum);
    if (op == OP_NONE) {
        std::printf("%s, \"volume_sum\": %s}\n", js.c_str(), num(vsum).c_str());
        return 0;
    }

    double ms, volume;
    size_t cells = 0, nv = 0, ne = 0, nf = 0;
    try {
        double t0 = now_ms();
        Nef r = nefs[0];
        if (op == OP_DIFFERENCE && nefs.size() > 1) {
            Nef rest = nefs[1];
            for (size_t i = 2; i < nefs.size(); i++) rest = rest + nefs[i];
            r = r - rest;
        } else if (op == OP_CONTACT) {
            r = r.boundary();
            for (size_t i = 1; i < nefs.size(); i++) r = r * nefs[i].boundary();
        } else {
            for (size_t i = 1; i < nefs.size(); i++) r = op == OP_UNION ? r + nefs[i] : r * nefs[i];
        }
        ms = now_ms() - t0;
        volume = measure(r, &cells);
        count(r, &nv, &ne, &nf);
    } catch (const std::exception &e) {
        std::fprintf(stderr, "cgal_nef: %s failed: %s\n", op_names[op], e.what());
        return 2;
    }
    std::printf("%s, \"volume\": %s, \"volumes\": %zu, \"vertices\": %zu, \"edges\": %zu, "
                "\"facets\": %zu, \"ms\": %.3f}\n",
                js.c_str(), num(volume).c_str(), cells, nv, ne, nf, ms);
    return 0;
}
