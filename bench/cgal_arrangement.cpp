/* cgal_arrangement.cpp — the CGAL peer of the 2D benchmark.
 *
 * Usage: cgal_arrangement REQUEST.json
 * Reads a cellar request {"kind": "lines", "lines": [[[x1, y1], [x2, y2]], ...], ...} (options
 * are ignored), builds the exact arrangement with CGAL::Arrangement_2 (Epeck kernel, segment
 * traits, aggregated sweep-line insertion; zero-length segments skipped) and prints one JSON
 * line:
 *   {"V": vertices, "E": edges, "F": bounded faces,
 *    "V_nodangling": .., "E_nodangling": .., "ms": wall time of the insertion only}
 * V and E count every vertex and edge (like cellar with keep_dangling); the _nodangling counts
 * are those left after removing every edge with the same face on both sides (in a plane
 * embedding these are exactly the bridges and dangling trees) and the vertices that this
 * leaves isolated (like cellar without keep_dangling).  That removal runs after the timing,
 * on the arrangement itself, which is not needed afterwards.
 * Exit status 0 on success, 1 on a bad request, 2 on a CGAL failure.
 */
#include <CGAL/Arr_segment_traits_2.h>
#include <CGAL/Arrangement_2.h>
#include <CGAL/Exact_predicates_exact_constructions_kernel.h>

#include <jansson.h>

#include <chrono>
#include <cstdio>
#include <exception>
#include <vector>

typedef CGAL::Exact_predicates_exact_constructions_kernel Kernel;
typedef CGAL::Arr_segment_traits_2<Kernel> Traits;
typedef Traits::Point_2 Point;
typedef Traits::Curve_2 Segment;
typedef CGAL::Arrangement_2<Traits> Arrangement;

/* One point [x, y] into xy[0..1]; true on success. */
static bool read_point(const json_t *p, double *xy)
{
    if (!json_is_array(p) || json_array_size(p) != 2) return false;
    for (size_t k = 0; k < 2; k++) {
        const json_t *c = json_array_get(p, k);
        if (!json_is_number(c)) return false;
        xy[k] = json_number_value(c);
    }
    return true;
}

/* The non-degenerate segments of a request; false (with why) on a bad request. */
static bool read_segments(const char *path, std::vector<Segment> &out, char *why, size_t whylen)
{
    json_error_t jerr;
    json_t *req = json_load_file(path, 0, &jerr);
    if (!req) {
        std::snprintf(why, whylen, "%d:%d: %s", jerr.line, jerr.column, jerr.text);
        return false;
    }
    const json_t *lines = json_object_get(req, "lines");
    bool ok = json_is_array(lines);
    if (!ok) std::snprintf(why, whylen, "request has no \"lines\" array");
    for (size_t i = 0; ok && i < json_array_size(lines); i++) {
        const json_t *l = json_array_get(lines, i);
        double a[2], b[2];
        if (!json_is_array(l) || json_array_size(l) != 2 || !read_point(json_array_get(l, 0), a) ||
            !read_point(json_array_get(l, 1), b)) {
            std::snprintf(why, whylen, "lines[%zu] is not [[x1, y1], [x2, y2]]", i);
            ok = false;
            break;
        }
        if (a[0] == b[0] && a[1] == b[1]) continue;
        out.push_back(Segment(Point(a[0], a[1]), Point(b[0], b[1])));
    }
    json_decref(req);
    return ok;
}

/* Removes the edges with the same face on both sides until none is left (one pass suffices
 * in theory, since removing such an edge merges no faces; the loop makes sure). */
static void remove_dangling(Arrangement &arr)
{
    for (;;) {
        std::vector<Arrangement::Halfedge_handle> dangling;
        for (auto e = arr.edges_begin(); e != arr.edges_end(); ++e)
            if (e->face() == e->twin()->face()) dangling.push_back(e);
        if (dangling.empty()) break;
        /* remove_edge() also removes an end vertex that becomes isolated. */
        for (auto he : dangling) arr.remove_edge(he);
    }
}

int main(int argc, char **argv)
{
    if (argc != 2) {
        std::fprintf(stderr, "usage: %s REQUEST.json\n", argv[0]);
        return 1;
    }
    std::vector<Segment> segments;
    char why[256];
    if (!read_segments(argv[1], segments, why, sizeof why)) {
        std::fprintf(stderr, "%s: %s\n", argv[1], why);
        return 1;
    }

    try {
        Arrangement arr;
        auto t0 = std::chrono::steady_clock::now();
        CGAL::insert(arr, segments.begin(), segments.end());
        auto t1 = std::chrono::steady_clock::now();
        double ms = std::chrono::duration<double, std::milli>(t1 - t0).count();

        size_t nv = arr.number_of_vertices();
        size_t ne = arr.number_of_edges();
        size_t nf = arr.number_of_faces() - arr.number_of_unbounded_faces();

        remove_dangling(arr);
        size_t nv_nd = arr.number_of_vertices() - arr.number_of_isolated_vertices();
        size_t ne_nd = arr.number_of_edges();

        std::printf("{\"V\":%zu,\"E\":%zu,\"F\":%zu,\"V_nodangling\":%zu,\"E_nodangling\":%zu,"
                    "\"ms\":%.3f}\n",
                    nv, ne, nf, nv_nd, ne_nd, ms);
    } catch (const std::exception &ex) {
        std::fprintf(stderr, "%s: CGAL: %s\n", argv[1], ex.what());
        return 2;
    }
    return 0;
}
