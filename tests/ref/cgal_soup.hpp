/* cgal_soup.hpp — what the CGAL reference programs (cgal_bool.cpp, cgal_nef.cpp) share: solids
 * as read (doubles and index polygons, as cellar reads them), their OFF and OBJ readers, the
 * checked outward mesh of a soup, and numbers printed to round-trip.  Include it after the
 * typedefs of Kernel, Point and Mesh (a CGAL::Surface_mesh of Kernel points) and the CGAL
 * headers they need; a header of one translation unit each, so its functions are static.
 */
#ifndef CELLAR_CGAL_SOUP_HPP
#define CELLAR_CGAL_SOUP_HPP

typedef CGAL::Epick::Point_3 Dpoint; /* a point of doubles, as read */
typedef std::vector<std::size_t> Polygon;

/* One solid as read: doubles and index polygons, and where it came from. */
struct Soup {
    std::string label; /* "file.obj" or "file.obj:g cell2" */
    std::vector<Dpoint> points;
    std::vector<Polygon> polygons;
};

static double now_ms()
{
    using namespace std::chrono;
    return duration<double, std::milli>(steady_clock::now().time_since_epoch()).count();
}

/* ---- reading ------------------------------------------------------------------------------ */

/* ---- reading ------------------------------------------------------------------------------ */

static bool ends_with(const std::string &s, const char *suffix)
{
    size_t n = std::strlen(suffix);
    if (s.size() < n) return false;
    for (size_t i = 0; i < n; i++)
        if (std::tolower((unsigned char)s[s.size() - n + i]) != suffix[i]) return false;
    return true;
}

/* OFF through CGAL's reader, into Epick points: doubles, as cellar reads them (an Epeck point
 * read from a stream would take "0.1" as the exact rational 1/10). */
static bool read_off(const std::string &path, std::vector<Soup> &out, std::string &why)
{
    std::ifstream in(path);
    if (!in) {
        why = "cannot open";
        return false;
    }
    Soup s;
    s.label = path;
    if (!CGAL::IO::read_OFF(in, s.points, s.polygons, CGAL::parameters::verbose(false))) {
        why = "not a readable OFF file";
        return false;
    }
    out.push_back(std::move(s));
    return true;
}

/* OBJ: "v x y z", "f a b c ..." (a, a/t, a//n, a/t/n; negative = relative to the end), other
 * statements ignored.  With groups, each "g"/"o" statement starts a new solid, sharing the
 * file's vertex list (the soups are trimmed of unused points later). */
static bool read_obj(const std::string &path, bool groups, std::vector<Soup> &out, std::string &why)
{
    std::ifstream in(path);
    if (!in) {
        why = "cannot open";
        return false;
    }
    std::vector<Dpoint> pts;
    std::vector<std::pair<std::string, std::vector<Polygon>>> parts(1);
    parts[0].first = path;
    std::string line;
    for (size_t ln = 1; std::getline(in, line); ln++) {
        const char *c = line.c_str();
        while (*c == ' ' || *c == '\t') c++;
        char *end;
        if (c[0] == 'v' && (c[1] == ' ' || c[1] == '\t')) {
            double p[3];
            const char *q = c + 1;
            for (int k = 0; k < 3; k++) {
                p[k] = std::strtod(q, &end);
                if (end == q || !std::isfinite(p[k])) {
                    why = "line " + std::to_string(ln) + ": bad vertex";
                    return false;
                }
                q = end;
            }
            pts.emplace_back(p[0], p[1], p[2]);
        } else if (c[0] == 'f' && (c[1] == ' ' || c[1] == '\t')) {
            Polygon poly;
            const char *q = c + 1;
            for (;;) {
                while (*q == ' ' || *q == '\t' || *q == '\r') q++;
                if (!*q) break;
                long i = std::strtol(q, &end, 10);
                if (end == q) {
                    why = "line " + std::to_string(ln) + ": bad face";
                    return false;
                }
                q = end;
                while (*q && *q != ' ' && *q != '\t' && *q != '\r') q++; /* /t/n */
                long idx = i > 0 ? i - 1 : (long)pts.size() + i;
                if (i == 0 || idx < 0 || idx >= (long)pts.size()) {
                    why = "line " + std::to_string(ln) + ": vertex index out of range";
                    return false;
                }
                poly.push_back((size_t)idx);
            }
            if (poly.size() < 3) {
                why = "line " + std::to_string(ln) + ": face with fewer than 3 vertices";
                return false;
            }
            parts.back().second.push_back(std::move(poly));
        } else if (groups && (c[0] == 'g' || c[0] == 'o') && (c[1] == ' ' || c[1] == '\t')) {
            std::string name = c;
            while (!name.empty() && (name.back() == '\r' || name.back() == ' ')) name.pop_back();
            parts.emplace_back(path + ":" + name, std::vector<Polygon>());
        }
    }
    for (auto &part : parts) {
        if (part.second.empty()) continue; /* faces before the first group, empty groups */
        Soup s;
        s.label = part.first;
        s.points = pts;
        s.polygons = std::move(part.second);
        out.push_back(std::move(s));
    }
    if (out.empty()) why = "no faces";
    return !out.empty();
}

/* ---- meshes ------------------------------------------------------------------------------- */

/* A soup into a checked, triangulated, outward mesh; false with why. */
static bool make_mesh(Soup &s, Mesh &m, std::string &why)
{
    PMP::repair_polygon_soup(s.points, s.polygons); /* merges equal points, drops unused ones */
    if (s.polygons.empty()) {
        why = "no faces left after removing degenerate ones";
        return false;
    }
    if (!PMP::orient_polygon_soup(s.points, s.polygons)) {
        why = "not an orientable 2-manifold (an edge on more than two faces, or a pinched vertex)";
        return false;
    }
    std::vector<Point> pts;
    pts.reserve(s.points.size());
    for (const Dpoint &p : s.points) pts.emplace_back(p.x(), p.y(), p.z());
    if (!PMP::is_polygon_soup_a_polygon_mesh(s.polygons)) {
        why = "the faces do not make a polygon mesh";
        return false;
    }
    PMP::polygon_soup_to_polygon_mesh(pts, s.polygons, m);
    if (!PMP::triangulate_faces(m)) {
        why = "a face could not be triangulated";
        return false;
    }
    if (!CGAL::is_closed(m)) {
        why = "not closed";
        return false;
    }
    if (PMP::does_self_intersect(m)) {
        why = "self-intersecting";
        return false;
    }
    /* does_bound_a_volume() accepts an inward cube (it checks nesting, not outwardness). */
    PMP::orient_to_bound_a_volume(m);
    if (!PMP::does_bound_a_volume(m)) {
        why = "does not bound a volume (components intersect)";
        return false;
    }
    return true;
}

static std::string num(double x)
{
    char b[32];
    if (!std::isfinite(x)) return "null";
    std::snprintf(b, sizeof b, "%.17g", x);
    return b;
}

/* The start of a reference's JSON line, {"op": op, "kernel": kernel, "inputs": n,
 * "input_volumes": [...] (left open for the rest); *vsum gets the volumes' sum. */
static std::string result_head(const char *op, const char *kernel, size_t n,
                               const std::vector<double> &vols, double *vsum)
{
    std::string js = "{\"op\": \"" + std::string(op) + "\", \"kernel\": \"" + kernel +
                     "\", \"inputs\": " + std::to_string(n) + ", \"input_volumes\": [";
    *vsum = 0;
    for (size_t i = 0; i < vols.size(); i++) {
        if (i) js += ", ";
        js += num(vols[i]);
        *vsum += vols[i];
    }
    return js + "]";
}

#endif
