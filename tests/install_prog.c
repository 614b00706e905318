/* install_prog.c — a user's program of the installed library (tests/t_install.sh): it sees only
 * <cellar.h> and what `pkg-config --cflags --libs cellar` gives, and checks each entry point on
 * a case whose answer is known:
 *   - cellar_version() is the header's CELLAR_VERSION_*;
 *   - the four sides and two diagonals of a square: 5 vertices, 8 edges, 4 faces;
 *   - the union of the squares [0,2]^2 and [1,3]^2: result.area 7 exactly;
 *   - the union of two unit cubes, one moved by 0.5 along x, y and z: result.volume 1.875;
 *   - a segment with a NaN coordinate: 422 and a message naming that segment;
 *   - cellar_run_json() on a lines request, and on a body that is not JSON (400).
 * It also defines functions named as internal functions of the library (sort_u64, svg_read,
 * ...): linked with the static library they would clash unless only cellar_* names are
 * global in it, and a call to them must reach these, not the library's.
 * Prints "ok NAME" / "FAIL NAME" per check and "N passed, N failed" last; exits 1 on a failure.
 * Threads: one.  Ownership: every result is freed (the sanitized build checks leaks). */
#include <cellar.h>

#include <math.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

static int P, F;

static void check(const char *name, int ok)
{
    if (ok) {
        P++;
        printf("ok %s\n", name);
    } else {
        F++;
        printf("FAIL %s\n", name);
    }
}

/* Our own functions named as the library's internal ones: with the internal names global in
 * the static library, the link fails (multiple definition) or a call lands in the library. */
int sort_u64(void);
int svg_read(void);
int box_tree_build(void);
int plane_canon(void);
int sort_u64(void)
{
    return 1;
}
int svg_read(void)
{
    return 2;
}
int box_tree_build(void)
{
    return 3;
}
int plane_canon(void)
{
    return 4;
}

static size_t rows(const cellar_result *r, const char *name)
{
    const cellar_array *a = cellar_result_get(r, name);
    return a ? a->rows : (size_t)-1;
}

/* the one double of a 1 x 1 F64 array, NAN when there is none */
static double scalar(const cellar_result *r, const char *name)
{
    const cellar_array *a = cellar_result_get(r, name);
    if (!a || a->dtype != CELLAR_F64 || a->rows != 1 || a->cols != 1 || !a->data) return NAN;
    return *(const double *)a->data;
}

static void lines(void)
{
    /* the square's four sides and its two diagonals */
    const double seg[] = {0, 0, 2, 0, 2, 0, 2, 2, 2, 2, 0, 2, 0, 2, 0, 0, 0, 0, 2, 2, 0, 2, 2, 0};
    cellar_result *r = NULL;
    cellar_error e;
    int rc = cellar_arrangement2d(seg, 6, NULL, &r, &e);
    check("cellar_arrangement2d returns CELLAR_OK", rc == CELLAR_OK && e.status == 0 && r);
    if (!r) return;
    const cellar_array *V = cellar_result_get(r, "V");
    check("lines: V is 5 x 2 doubles",
          V && V->dtype == CELLAR_F64 && V->rows == 5 && V->cols == 2 && V->data);
    check("lines: 8 edges (EV)", rows(r, "EV") == 8);
    check("lines: 4 faces (FV.indptr has 5 rows)", rows(r, "FV.indptr") == 5);
    check("lines: cellar_result_dim is 2", cellar_result_dim(r) == 2);
    size_t n = cellar_result_count(r), named = 0;
    for (size_t i = 0; i < n; i++) {
        const cellar_array *a = cellar_result_array(r, i);
        named += a && a->name && cellar_result_get(r, a->name) == a;
    }
    check("lines: every array is found by its name", n > 0 && named == n);
    const char *js = cellar_result_json(r);
    check("lines: cellar_result_json starts {\"dim\":2", js && strncmp(js, "{\"dim\":2", 8) == 0);
    cellar_result_free(r);

    /* a NaN coordinate: the message names the segment */
    double bad[] = {0, 0, 1, 1, 0, 1, NAN, 0};
    r = NULL;
    rc = cellar_arrangement2d(bad, 2, NULL, &r, &e);
    printf("  NaN: status %d, \"%s\"\n", rc, e.msg);
    check("a NaN coordinate: 422", rc == CELLAR_EINVALID && e.status == CELLAR_EINVALID && !r);
    check("a NaN coordinate: the message names segments[1]", strstr(e.msg, "segments[1]") != NULL);
    cellar_result_free(r);
    rc = cellar_arrangement2d(bad, 2, NULL, &r, NULL);
    check("a NaN coordinate with a NULL cellar_error: 422", rc == CELLAR_EINVALID);
}

static void polygons(void)
{
    /* [0,2]^2 and [1,3]^2, one ring each */
    const uint32_t poly_off[] = {0, 1, 2}, ring_off[] = {0, 4, 8};
    const double xy[] = {0, 0, 2, 0, 2, 2, 0, 2, 1, 1, 3, 1, 3, 3, 1, 3};
    cellar_result *r = NULL;
    cellar_error e;
    int rc = cellar_polygons(2, poly_off, ring_off, xy, "union", NULL, &r, &e);
    check("cellar_polygons union returns CELLAR_OK", rc == CELLAR_OK && r);
    if (!r) {
        printf("  %d %s\n", rc, e.msg);
        return;
    }
    double a = scalar(r, "result.area");
    printf("  union area %.17g\n", a);
    check("polygons: the union's result.area is 7 exactly", a == 7.0);
    cellar_result_free(r);
}

static void solids(void)
{
    /* a unit cube as 12 triangles, counter-clockwise seen from outside */
    static const uint32_t F[] = {0, 2, 1, 0, 3, 2, 4, 5, 6, 4, 6, 7, 0, 1, 5, 0, 5, 4,
                                 2, 3, 7, 2, 7, 6, 1, 2, 6, 1, 6, 5, 0, 4, 7, 0, 7, 3};
    double V[2][24];
    for (int c = 0; c < 2; c++)
        for (int i = 0; i < 8; i++) {
            double d = c ? 0.5 : 0;
            V[c][3 * i] = ((i == 1 || i == 2 || i == 5 || i == 6) ? 1 : 0) + d;
            V[c][3 * i + 1] = ((i == 2 || i == 3 || i == 6 || i == 7) ? 1 : 0) + d;
            V[c][3 * i + 2] = (i >= 4 ? 1 : 0) + d;
        }
    cellar_solid s[2] = {{V[0], 8, F, NULL, 12}, {V[1], 8, F, NULL, 12}};
    cellar_options o;
    memset(&o, 0, sizeof o);
    o.threads = 2;
    cellar_result *r = NULL;
    cellar_error e;
    int rc = cellar_solids(s, 2, "union", &o, &r, &e);
    check("cellar_solids union returns CELLAR_OK", rc == CELLAR_OK && r);
    if (!r) {
        printf("  %d %s\n", rc, e.msg);
        return;
    }
    double v = scalar(r, "result.volume");
    printf("  union volume %.17g\n", v);
    check("solids: the union's result.volume is 1.875", v == 1.875);
    check("solids: cellar_result_dim is 3", cellar_result_dim(r) == 3);
    cellar_result_free(r);
}

static void run_json(void)
{
    const char *req = "{\"kind\": \"lines\", \"lines\": [[[0, 0], [1, 1]], [[0, 1], [1, 0]]]}";
    char *out = NULL;
    size_t len = 0;
    cellar_error e;
    int rc = cellar_run_json(req, strlen(req), NULL, &out, &len, &e);
    check("cellar_run_json: a lines request gives a 2D result",
          rc == CELLAR_OK && out && len > 0 && strstr(out, "\"dim\":2") && out[len - 1] == '\n');
    cellar_free(out);
    out = NULL;
    rc = cellar_run_json("{", 1, NULL, &out, &len, &e);
    check("cellar_run_json: a body that is not JSON is 400", rc == CELLAR_EJSON && !out);
    cellar_free(out);
}

int main(void)
{
    char want[32];
    snprintf(want, sizeof want, "%d.%d.%d", CELLAR_VERSION_MAJOR, CELLAR_VERSION_MINOR,
             CELLAR_VERSION_PATCH);
    const char *v = cellar_version();
    printf("  cellar_version %s\n", v ? v : "(null)");
    check("cellar_version is the header's", v && strcmp(v, want) == 0);
    check("cellar_stage_name(\"lines\", 0) names a stage", cellar_stage_name("lines", 0) != NULL);
    check("our own sort_u64, svg_read, box_tree_build, plane_canon are called",
          sort_u64() == 1 && svg_read() == 2 && box_tree_build() == 3 && plane_canon() == 4);
    lines();
    polygons();
    solids();
    run_json();
    printf("%d passed, %d failed\n", P, F);
    return F ? 1 : 0;
}
