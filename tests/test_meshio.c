/* test_meshio.c — meshes in and out (api/meshio.h, the stl/off/3mf/glb rows of api/render.h):
 * STL binary and ASCII (exact welding: a cube of 12 triangles is 8 vertices; a binary file whose
 * header says "solid" is binary by its size), PLY ascii and binary of both byte orders (other
 * elements and properties skipped), 3MF with build and component transforms (a mirroring one
 * reverses the triangles), the errors of each naming where, the request of mesh files, and
 * round trips: a result written as STL, OFF and 3MF read back to the same volume and cells; OBJ
 * and the others hold only the vertices their triangles use. */
#include "tests/check.h"

#include "api/api.h"
#include "api/meshio.h"
#include "api/render.h"
#include "core/solid.h"

#include <jansson.h>
#include <math.h>
#include <stdint.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <zip.h>

static const double CUBE_V[8][3] = {{0, 0, 0}, {1, 0, 0}, {1, 1, 0}, {0, 1, 0},
                                    {0, 0, 1}, {1, 0, 1}, {1, 1, 1}, {0, 1, 1}};
/* outward triangles of the unit cube */
static const int CUBE_T[12][3] = {{0, 3, 2}, {0, 2, 1}, {4, 5, 6}, {4, 6, 7}, {0, 1, 5}, {0, 5, 4},
                                  {1, 2, 6}, {1, 6, 5}, {2, 3, 7}, {2, 7, 6}, {3, 0, 4}, {3, 4, 7}};

static double volume_of(const solid *s)
{
    solid_report rep;
    memset(&rep, 0, sizeof rep);
    if (solid_check(s, 1.0 / 1024, "s", &rep, NULL) != 0) return NAN;
    return rep.volume;
}

static char *cube_ascii(size_t *len)
{
    char *buf = NULL;
    FILE *f = open_memstream(&buf, len);
    fprintf(f, "solid cube\n");
    for (int t = 0; t < 12; t++) {
        fprintf(f, "  facet normal 0 0 0\n    outer loop\n");
        for (int k = 0; k < 3; k++)
            fprintf(f, "      vertex %g %g %g\n", CUBE_V[CUBE_T[t][k]][0], CUBE_V[CUBE_T[t][k]][1],
                    CUBE_V[CUBE_T[t][k]][2]);
        fprintf(f, "    endloop\n  endfacet\n");
    }
    fprintf(f, "endsolid cube\n");
    fclose(f);
    return buf;
}

static void le32(unsigned char *p, uint32_t v)
{
    for (int i = 0; i < 4; i++) p[i] = (unsigned char)(v >> (8 * i));
}

static unsigned char *cube_binary(const char *header, size_t *len)
{
    *len = 84 + 50 * 12;
    unsigned char *b = calloc(1, *len);
    memcpy(b, header, strlen(header));
    le32(b + 80, 12);
    for (int t = 0; t < 12; t++)
        for (int k = 0; k < 3; k++)
            for (int a = 0; a < 3; a++) {
                float f = (float)CUBE_V[CUBE_T[t][k]][a];
                uint32_t u;
                memcpy(&u, &f, 4);
                le32(b + 84 + 50 * t + 12 + 12 * k + 4 * a, u);
            }
    return b;
}

TEST(stl_ascii_welds)
{
    size_t len;
    char *t = cube_ascii(&len), err[200];
    solid s;
    REQUIRE(mesh_read_stl(t, len, &s, err, sizeof err) == 0, "%s", err);
    CHECK(s.nv == 8 && s.nf == 12, "%zu vertices, %zu faces (8, 12)", s.nv, s.nf);
    CHECK(fabs(volume_of(&s) - 1) < 1e-12, "volume %g", volume_of(&s));
    solid_free(&s);
    /* -0 is 0: one vertex */
    const char *z = "solid z\nfacet normal 0 0 1\nouter loop\nvertex 0 0 0\nvertex 1 0 0\n"
                    "vertex 0 1 0\nendloop\nendfacet\nfacet normal 0 0 1\nouter loop\nvertex -0 0 "
                    "0\nvertex 0 1 0\nvertex -1 0 0\nendloop\nendfacet\nendsolid z\n";
    REQUIRE(mesh_read_stl(z, strlen(z), &s, err, sizeof err) == 0, "%s", err);
    CHECK(s.nv == 4, "%zu vertices (4: -0 welded to 0)", s.nv);
    solid_free(&s);
    /* bit-exact only: 1 and 1.0000000000000002 stay apart */
    const char *n = "solid z\nfacet normal 0 0 1\nouter loop\nvertex 1 0 0\nvertex 0 1 0\n"
                    "vertex 1.0000000000000002 0 0\nendloop\nendfacet\nendsolid\n";
    REQUIRE(mesh_read_stl(n, strlen(n), &s, err, sizeof err) == 0, "%s", err);
    CHECK(s.nv == 3, "%zu vertices (3: no tolerance)", s.nv);
    solid_free(&s);
    free(t);
}

TEST(stl_binary_welds)
{
    size_t len;
    char err[200];
    solid s;
    /* a binary file whose header starts with "solid": binary, by its size */
    unsigned char *b = cube_binary("solid cube (binary, really)", &len);
    REQUIRE(mesh_read_stl((char *)b, len, &s, err, sizeof err) == 0, "%s", err);
    CHECK(s.nv == 8 && s.nf == 12, "%zu vertices, %zu faces (8, 12)", s.nv, s.nf);
    CHECK(fabs(volume_of(&s) - 1) < 1e-12, "volume %g", volume_of(&s));
    solid_free(&s);
    /* one byte short: neither */
    unsigned char *x = cube_binary("x", &len);
    CHECK(mesh_read_stl((char *)x, len - 1, &s, err, sizeof err) == -1 &&
              strstr(err, "binary STL of 12 triangles is 684 bytes, this is 683"),
          "%s", err);
    free(x);
    CHECK(mesh_read_stl((char *)b, len - 1, &s, err, sizeof err) == -1 && strstr(err, "line 1"),
          "short \"solid\" binary: %s", err);
    CHECK(s.nv == 0 && !s.V, "refused with a solid");
    CHECK(mesh_read_stl("abc", 3, &s, err, sizeof err) == -1 && strstr(err, "3 bytes"), "%s", err);
    /* a coordinate not finite: named by triangle and vertex */
    uint32_t inf = 0x7f800000u;
    unsigned char *c = cube_binary("x", &len);
    le32(c + 84 + 50 * 7 + 12 + 12 * 2 + 4, inf);
    CHECK(mesh_read_stl((char *)c, len, &s, err, sizeof err) == -1 &&
              !strcmp(err, "triangle 7: vertex 2: coordinate not finite"),
          "%s", err);
    free(b);
    free(c);
}

TEST(stl_ascii_errors)
{
    char err[200];
    solid s;
    const char *cases[][2] = {
        {"solid a\nfacet normal 0 0 1\nouter loop\nvertex 0 0 0\nvertex 1 0\n", "line 6:"},
        {"solid a\nfacet normal 0 0 1\nouter loop\nvertex 0 0 0\nendloop\nendfacet\nendsolid\n",
         "facet 0: 1 vertices"},
        {"solid a\nfacet nromal 0 0 1\n", "line 2: expected \"normal\""},
        {"solid a\nfacet normal 0 0 1\nouter loop\nvertex 0 0 0\nvertex 1 0 0\nvertex 0 1 "
         "nan\nendloop\nendfacet\nendsolid\n",
         "line 6: expected a finite number"},
        {"solid a\n", "expected \"facet\" or \"endsolid\", got the end of the file"},
    };
    for (size_t i = 0; i < sizeof cases / sizeof *cases; i++) {
        int rc = mesh_read_stl(cases[i][0], strlen(cases[i][0]), &s, err, sizeof err);
        CHECK(rc == -1 && strstr(err, cases[i][1]), "case %zu: %d \"%s\" (want \"%s\")", i, rc, err,
              cases[i][1]);
    }
}

static const char PLY_ASCII[] = "ply\nformat ascii 1.0\ncomment a cube\nelement vertex 8\n"
                                "property float x\nproperty float y\nproperty float z\n"
                                "property uchar red\nelement face 6\n"
                                "property list uchar int vertex_indices\nelement edge 1\n"
                                "property int vertex1\nproperty int vertex2\nend_header\n"
                                "0 0 0 1\n1 0 0 1\n1 1 0 1\n0 1 0 1\n0 0 1 1\n1 0 1 1\n1 1 1 1\n"
                                "0 1 1 1\n4 0 3 2 1\n4 4 5 6 7\n4 0 1 5 4\n4 1 2 6 5\n4 2 3 7 6\n"
                                "4 3 0 4 7\n0 1\n";

/* The cube as binary PLY: vertices double x, int tag, float y, z; faces uint count, ushort
 * indices, and an element before them that is skipped. */
static unsigned char *ply_binary(int big, size_t *len)
{
    static const int Q[6][4] = {{0, 3, 2, 1}, {4, 5, 6, 7}, {0, 1, 5, 4},
                                {1, 2, 6, 5}, {2, 3, 7, 6}, {3, 0, 4, 7}};
    char head[512];
    int hn = snprintf(head, sizeof head,
                      "ply\r\nformat %s 1.0\r\nelement junk 2\r\nproperty list uchar short j\r\n"
                      "element vertex 8\r\nproperty double x\r\nproperty int tag\r\n"
                      "property float y\r\nproperty float z\r\nelement face 6\r\n"
                      "property list uint ushort vertex_index\r\nend_header\n",
                      big ? "binary_big_endian" : "binary_little_endian");
    unsigned char *b = malloc(4096), *p = b + hn;
    memcpy(b, head, (size_t)hn);
#define PUT(v)                                                                                     \
    do {                                                                                           \
        unsigned char tmp[8];                                                                      \
        memcpy(tmp, &(v), sizeof(v));                                                              \
        for (size_t i_ = 0; i_ < sizeof(v); i_++) *p++ = tmp[big ? sizeof(v) - 1 - i_ : i_];       \
    } while (0)
    uint8_t two = 2;
    int16_t js[2] = {-5, 7};
    for (int k = 0; k < 2; k++) {
        PUT(two);
        PUT(js[0]);
        PUT(js[1]);
    }
    for (int v = 0; v < 8; v++) {
        double x = CUBE_V[v][0];
        int32_t tag = v;
        float y = (float)CUBE_V[v][1], z = (float)CUBE_V[v][2];
        PUT(x);
        PUT(tag);
        PUT(y);
        PUT(z);
    }
    for (int f = 0; f < 6; f++) {
        uint32_t four = 4;
        PUT(four);
        for (int k = 0; k < 4; k++) {
            uint16_t ix = (uint16_t)Q[f][k];
            PUT(ix);
        }
    }
#undef PUT
    *len = (size_t)(p - b);
    return b;
}

TEST(ply_reads)
{
    char err[200];
    solid s;
    REQUIRE(mesh_read_ply(PLY_ASCII, strlen(PLY_ASCII), &s, err, sizeof err) == 0, "%s", err);
    CHECK(s.nv == 8 && s.nf == 6 && s.cyc_off[1] == 4, "ascii: %zu vertices, %zu faces", s.nv,
          s.nf);
    CHECK(fabs(volume_of(&s) - 1) < 1e-12, "ascii volume %g", volume_of(&s));
    solid_free(&s);
    for (int big = 0; big < 2; big++) {
        size_t len;
        unsigned char *b = ply_binary(big, &len);
        REQUIRE(mesh_read_ply((char *)b, len, &s, err, sizeof err) == 0, "%s", err);
        CHECK(s.nv == 8 && s.nf == 6, "binary %d: %zu vertices, %zu faces", big, s.nv, s.nf);
        CHECK(fabs(volume_of(&s) - 1) < 1e-12, "binary %d volume %g", big, volume_of(&s));
        solid_free(&s);
        CHECK(mesh_read_ply((char *)b, len - 1, &s, err, sizeof err) == -1 &&
                  strstr(err, "face 5: vertex_index: the file ends"),
              "truncated: %s", err);
        free(b);
    }
}

TEST(ply_errors)
{
    char err[200];
    solid s;
    const char *cases[][2] = {
        {"ply\nformat ascii 1.0\nelement vertex 3\nproperty float x\nproperty float y\nproperty "
         "float z\nelement face 1\nproperty list uchar int vertex_indices\nend_header\n0 0 0\n1 0 "
         "0\n0 1 0\n3 0 1 3\n",
         "face 0: vertex index 3 not below the 3 vertices"},
        {"ply\nformat ascii 2.0\nend_header\n", "line 2: format: version 1.0 expected"},
        {"ply\nformat ascii 1.0\nelement vertex 1\nproperty float x\nend_header\n0\n",
         "element vertex: no scalar property x, y and z"},
        {"plyx\n", "line 1: expected \"ply\""},
        {"ply\nformat ascii 1.0\n", "header: no end_header line"},
        {"ply\nformat ascii 1.0\nelement vertex 1\nproperty float x\nproperty float y\nproperty "
         "float z\nend_header\n0 zero 0\n",
         "vertex 0: y: line 8: expected a finite number"},
        {"ply\nformat ascii 1.0\nelement vertex 1\nproperty float128 x\nend_header\n",
         "line 4: property: unknown type \"float128\""},
        {"ply\nformat ascii 1.0\nelement face 1\nproperty list uchar int vertex_indices\n"
         "end_header\n2 0 1\n",
         "face 0: 2 vertices"},
    };
    for (size_t i = 0; i < sizeof cases / sizeof *cases; i++) {
        int rc = mesh_read_ply(cases[i][0], strlen(cases[i][0]), &s, err, sizeof err);
        CHECK(rc == -1 && strstr(err, cases[i][1]), "case %zu: %d \"%s\" (want \"%s\")", i, rc, err,
              cases[i][1]);
    }
    /* a header longer than the limit */
    size_t n = MESH_PLY_HEADER + 100;
    char *big = malloc(n);
    memset(big, 'c', n);
    memcpy(big, "ply\n", 4);
    CHECK(mesh_read_ply(big, n, &s, err, sizeof err) == -1 && strstr(err, "longer than"), "%s",
          err);
    free(big);
}

/* A 3MF file of the given model text (and rels: NULL none), made with libzip. */
static char *make_3mf(const char *model, const char *rels, const char *model_name, size_t *len)
{
    zip_error_t ze;
    zip_error_init(&ze);
    zip_source_t *src = zip_source_buffer_create(NULL, 0, 0, &ze);
    zip_source_keep(src);
    zip_t *za = zip_open_from_source(src, ZIP_TRUNCATE, &ze);
    if (rels) zip_file_add(za, "_rels/.rels", zip_source_buffer(za, rels, strlen(rels), 0), 0);
    if (model) zip_file_add(za, model_name, zip_source_buffer(za, model, strlen(model), 0), 0);
    zip_close(za);
    zip_source_open(src);
    zip_source_seek(src, 0, SEEK_END);
    zip_int64_t n = zip_source_tell(src);
    zip_source_seek(src, 0, SEEK_SET);
    char *p = malloc((size_t)n);
    zip_source_read(src, p, (zip_uint64_t)n);
    zip_source_close(src);
    zip_source_free(src);
    *len = (size_t)n;
    return p;
}

static const char RELS[] =
    "<?xml version=\"1.0\"?><Relationships "
    "xmlns=\"http://schemas.openxmlformats.org/package/2006/relationships\"><Relationship "
    "Target=\"/3D/other.model\" Id=\"r\" "
    "Type=\"http://schemas.microsoft.com/3dmanufacturing/2013/01/3dmodel\"/></Relationships>";

static char *cube_model(const char *extra_objects, const char *build)
{
    char *buf = NULL;
    size_t n;
    FILE *f = open_memstream(&buf, &n);
    fprintf(f, "<?xml version=\"1.0\"?>\n<model unit=\"millimeter\" "
               "xmlns=\"http://schemas.microsoft.com/3dmanufacturing/core/2015/02\">\n"
               "<resources><object id=\"1\" type=\"model\"><mesh><vertices>\n");
    for (int v = 0; v < 8; v++)
        fprintf(f, "<vertex x=\"%g\" y=\"%g\" z=\"%g\"/>\n", CUBE_V[v][0], CUBE_V[v][1],
                CUBE_V[v][2]);
    fprintf(f, "</vertices><triangles>\n");
    for (int t = 0; t < 12; t++)
        fprintf(f, "<triangle v1=\"%d\" v2=\"%d\" v3=\"%d\"/>\n", CUBE_T[t][0], CUBE_T[t][1],
                CUBE_T[t][2]);
    fprintf(f, "</triangles></mesh></object>%s</resources><build>%s</build></model>\n",
            extra_objects, build);
    fclose(f);
    return buf;
}

TEST(threemf_transforms)
{
    char err[200];
    solid *p;
    size_t np, len;
    /* item 1: the cube moved by (10, 0, 0); item 2: object 2 = the cube scaled by 2 (component)
     * then moved by (0, 5, 0); item 3: the cube mirrored in x (its triangles reversed) */
    char *model = cube_model("<object id=\"2\"><components><component objectid=\"1\" "
                             "transform=\"2 0 0 0 2 0 0 0 2 0 0 0\"/></components></object>",
                             "<item objectid=\"1\" transform=\"1 0 0 0 1 0 0 0 1 10 0 0\"/>"
                             "<item objectid=\"2\" transform=\"1 0 0 0 1 0 0 0 1 0 5 0\"/>"
                             "<item objectid=\"1\" transform=\"-1 0 0 0 1 0 0 0 1 0 0 0\"/>");
    char *z = make_3mf(model, RELS, "3D/other.model", &len);
    REQUIRE(mesh_read_3mf(z, len, &p, &np, err, sizeof err) == 0, "%s", err);
    REQUIRE(np == 3, "%zu solids (3)", np);
    CHECK(p[0].nv == 8 && p[0].V[3 * 6] == 11 && p[0].V[3 * 6 + 1] == 1, "item 1 moved: %g %g",
          p[0].V[18], p[0].V[19]);
    CHECK(p[1].V[3 * 6] == 2 && p[1].V[3 * 6 + 1] == 7 && p[1].V[3 * 6 + 2] == 2,
          "item 2 scaled then moved: %g %g %g", p[1].V[18], p[1].V[19], p[1].V[20]);
    CHECK(fabs(volume_of(&p[0]) - 1) < 1e-12 && fabs(volume_of(&p[1]) - 8) < 1e-12, "volumes %g %g",
          volume_of(&p[0]), volume_of(&p[1]));
    /* mirrored: still outward (triangles reversed), so no face is flipped by the check */
    solid_report rep;
    memset(&rep, 0, sizeof rep);
    CHECK(solid_check(&p[2], 1.0 / 1024, "m", &rep, NULL) == 0 && rep.flipped_faces == 0 &&
              rep.volume > 0,
          "mirrored: flipped %zu, volume %g", rep.flipped_faces, rep.volume);
    for (size_t i = 0; i < np; i++) solid_free(&p[i]);
    free(p);
    free(z);
    /* no rels: 3D/3dmodel.model; no build items: each mesh object as it is */
    char *m2 = cube_model("", "");
    z = make_3mf(m2, NULL, "3D/3dmodel.model", &len);
    REQUIRE(mesh_read_3mf(z, len, &p, &np, err, sizeof err) == 0, "%s", err);
    CHECK(np == 1 && p[0].nv == 8 && p[0].nf == 12, "%zu solids", np);
    for (size_t i = 0; i < np; i++) solid_free(&p[i]);
    free(p);
    free(z);
    free(m2);
    free(model);
}

TEST(threemf_errors)
{
    char err[200];
    solid *p;
    size_t np, len;
    CHECK(mesh_read_3mf("PK\3\4 not really", 16, &p, &np, err, sizeof err) == -1 &&
              strstr(err, "not a zip"),
          "%s", err);
    char *z = make_3mf("<model/>", NULL, "3D/elsewhere.model", &len);
    CHECK(mesh_read_3mf(z, len, &p, &np, err, sizeof err) == -1 &&
              strstr(err, "no model part 3D/3dmodel.model"),
          "%s", err);
    free(z);
    const char *models[][2] = {
        {"<model><resources><object><mesh/></object></resources></model>",
         "line 1: <object> without an id"},
        {"<model><resources><object id=\"1\"><mesh><vertices><vertex x=\"1\" y=\"a\" "
         "z=\"0\"/></vertices></mesh></object></resources></model>",
         "<vertex> y: expected a finite number"},
        {"<model><resources><object id=\"1\"><mesh><vertices><vertex x=\"0\" y=\"0\" "
         "z=\"0\"/></vertices><triangles><triangle v1=\"0\" v2=\"0\" "
         "v3=\"4\"/></triangles></mesh></object></resources></model>",
         "object 1: triangle 0: v3 = 4 not below the 1 vertices"},
        {"<model><resources><object id=\"1\"><components><component objectid=\"1\"/>"
         "</components></object></resources><build><item objectid=\"1\"/></build></model>",
         "build item 0: components nested deeper than 16"},
        {"<model><build><item objectid=\"9\"/></build></model>",
         "build item 0: object 9: no such object"},
        {"<!DOCTYPE model [<!ENTITY a \"aaaa\">]><model/>", "a DTD (<!DOCTYPE>) is not allowed"},
        {"<model><resources>", "malformed XML"},
        {"<model><vertex x=\"0\" y=\"0\" z=\"0\"/></model>", "<vertex> outside an <object>"},
        {"<model><resources><object id=\"1\"/><object id=\"1\"/></resources></model>",
         "object id 1 twice"},
        {"<model><resources><object id=\"2\"><components><component objectid=\"1\" "
         "transform=\"1 0 0\"/></components></object></resources></model>",
         "<component> transform: expected 12 numbers"},
    };
    for (size_t i = 0; i < sizeof models / sizeof *models; i++) {
        z = make_3mf(models[i][0], NULL, "3D/3dmodel.model", &len);
        int rc = mesh_read_3mf(z, len, &p, &np, err, sizeof err);
        CHECK(rc == -1 && strstr(err, models[i][1]) && !p && !np,
              "case %zu: %d \"%s\" (want \"%s\")", i, rc, err, models[i][1]);
        free(z);
    }
    /* nesting beyond the limit */
    char *deep = malloc(100000);
    size_t k = 0;
    k += (size_t)sprintf(deep, "<model>");
    for (int i = 0; i < MESH_3MF_DEPTH + 2; i++) k += (size_t)sprintf(deep + k, "<a>");
    for (int i = 0; i < MESH_3MF_DEPTH + 2; i++) k += (size_t)sprintf(deep + k, "</a>");
    sprintf(deep + k, "</model>");
    z = make_3mf(deep, NULL, "3D/3dmodel.model", &len);
    CHECK(mesh_read_3mf(z, len, &p, &np, err, sizeof err) == -1 && strstr(err, "nested deeper"),
          "%s", err);
    free(z);
    free(deep);
}

/* The result of the solids request text (3D), malloc'd. */
static char *run(const char *req, size_t *len)
{
    api_error e;
    char *out = NULL;
    int rc = api_run_json(req, strlen(req), 1, &out, len, &e);
    if (rc != API_OK) {
        fprintf(stderr, "run: %s\n", e.msg);
        return NULL;
    }
    return out;
}

static const char TWO_CUBES[] =
    "{\"kind\":\"solids\",\"solids\":[{\"V\":[[0,0,0],[2,0,0],[2,2,0],[0,2,0],[0,0,2],[2,0,2],[2,"
    "2,2],[0,2,2]],\"FV\":[[0,3,2,1],[4,5,6,7],[0,1,5,4],[1,2,6,5],[2,3,7,6],[3,0,4,7]]},{\"V\":[["
    "1,1,1],[3,1,1],[3,3,1],[1,3,1],[1,1,3],[3,1,3],[3,3,3],[1,3,3]],\"FV\":[[0,3,2,1],[4,5,6,7],["
    "0,1,5,4],[1,2,6,5],[2,3,7,6],[3,0,4,7]]}]%s}";

static double total_volume(solid *p, size_t np)
{
    double v = 0;
    for (size_t i = 0; i < np; i++) v += volume_of(&p[i]);
    return v;
}

TEST(round_trips)
{
    char req[2048], err[200];
    size_t len, olen, np;
    solid s, *p;
    api_error e;
    char *out;
    /* the arrangement: 3 cells; the union: one solid of volume 8 + 8 - 1 */
    snprintf(req, sizeof req, TWO_CUBES, "");
    char *cells = run(req, &len);
    snprintf(req, sizeof req, TWO_CUBES, ",\"op\":\"union\"");
    size_t ulen;
    char *uni = run(req, &ulen);
    REQUIRE(cells && uni, "runs");

    REQUIRE(render_stl(uni, ulen, NULL, &out, &olen, &e) == API_OK, "%s", e.msg);
    CHECK(olen >= 84 && memcmp(out, "solid", 5) != 0, "the header does not say solid");
    REQUIRE(mesh_read_stl(out, olen, &s, err, sizeof err) == 0, "%s", err);
    CHECK(fabs(volume_of(&s) - 15) < 1e-9, "stl union volume %g (15)", volume_of(&s));
    solid_free(&s);
    free(out);

    REQUIRE(render_off(uni, ulen, NULL, &out, &olen, &e) == API_OK, "%s", e.msg);
    REQUIRE(solid_read_off(out, olen, &s, err, sizeof err) == 0, "%s", err);
    CHECK(fabs(volume_of(&s) - 15) < 1e-12, "off union volume %g (15)", volume_of(&s));
    solid_free(&s);
    free(out);

    REQUIRE(render_3mf(cells, len, NULL, &out, &olen, &e) == API_OK, "%s", e.msg);
    REQUIRE(mesh_read_3mf(out, olen, &p, &np, err, sizeof err) == 0, "%s", err);
    CHECK(np == 3, "3mf of the arrangement: %zu objects (3 cells)", np);
    CHECK(fabs(total_volume(p, np) - 15) < 1e-12, "3mf cells' volume %g (15)", total_volume(p, np));
    for (size_t i = 0; i < np; i++) solid_free(&p[i]);
    free(p);
    free(out);

    REQUIRE(render_3mf(uni, ulen, NULL, &out, &olen, &e) == API_OK, "%s", e.msg);
    REQUIRE(mesh_read_3mf(out, olen, &p, &np, err, sizeof err) == 0, "%s", err);
    CHECK(np == 1 && fabs(volume_of(&p[0]) - 15) < 1e-12, "3mf of the union: %zu objects", np);
    for (size_t i = 0; i < np; i++) solid_free(&p[i]);
    free(p);
    free(out);

    /* the arrangement read back from its 3MF, run again: the same cells */
    REQUIRE(render_3mf(cells, len, NULL, &out, &olen, &e) == API_OK, "%s", e.msg);
    mesh_file f = {"cells.3mf", MESH_3MF, out, olen};
    char *req2;
    size_t r2len;
    REQUIRE(mesh_request_json(&f, 1, NULL, 0, &req2, &r2len, &e) == API_OK, "%s", e.msg);
    size_t l3;
    char *again = run(req2, &l3);
    json_t *a = again ? json_loads(again, 0, NULL) : NULL, *b = json_loads(cells, 0, NULL);
    CHECK(a && b &&
              json_array_size(json_object_get(a, "CF")) ==
                  json_array_size(json_object_get(b, "CF")),
          "cells again: %zu (%zu)", json_array_size(json_object_get(a, "CF")),
          json_array_size(json_object_get(b, "CF")));
    json_decref(a);
    json_decref(b);
    free(again);
    free(req2);
    free(out);
    free(cells);
    free(uni);
}

/* OBJ of a Boolean's result: every "v" line is used by an "f" line. */
TEST(obj_used_vertices)
{
    char req[2048];
    size_t len, olen;
    api_error e;
    char *out;
    snprintf(req, sizeof req, TWO_CUBES, ",\"op\":\"intersection\"");
    char *res = run(req, &len);
    REQUIRE(res, "run");
    REQUIRE(render_obj(res, len, NULL, &out, &olen, &e) == API_OK, "%s", e.msg);
    size_t nv = 0, used_n = 0;
    char used[4096] = {0};
    for (char *line = strtok(out, "\n"); line; line = strtok(NULL, "\n")) {
        unsigned a, b, c;
        if (line[0] == 'v') nv++;
        if (sscanf(line, "f %u %u %u", &a, &b, &c) == 3 && a < 4096 && b < 4096 && c < 4096)
            used[a] = used[b] = used[c] = 1;
    }
    for (size_t i = 1; i < 4096; i++) used_n += used[i];
    CHECK(nv == 8 && used_n == nv, "%zu v lines, %zu used (8: the intersection's cube)", nv,
          used_n);
    free(out);
    free(res);
}

TEST(request_of_files)
{
    size_t len;
    char *t = cube_ascii(&len), *out;
    size_t olen;
    api_error e;
    mesh_file f[2] = {{"a.stl", MESH_STL, t, len},
                      {"b.ply", MESH_PLY, PLY_ASCII, strlen(PLY_ASCII)}};
    const char *r = "{\"op\":\"union\",\"options\":{\"precision\":0.001}}";
    REQUIRE(mesh_request_json(f, 2, r, strlen(r), &out, &olen, &e) == API_OK, "%s", e.msg);
    json_t *j = json_loadb(out, olen, 0, NULL);
    CHECK(j && json_array_size(json_object_get(j, "solids")) == 2 &&
              !strcmp(json_string_value(json_object_get(j, "op")), "union") &&
              !strcmp(json_string_value(json_object_get(j, "kind")), "solids"),
          "%s", out);
    json_decref(j);
    free(out);
    const char *bad[][2] = {{"{\"solids\":[]}", "request: the solids are the files"},
                            {"[1]", "request: expected a JSON object"},
                            {"{\"kind\":\"lines\"}", "request.kind"},
                            {"{", "request: not JSON"}};
    for (size_t i = 0; i < 4; i++)
        CHECK(mesh_request_json(f, 2, bad[i][0], strlen(bad[i][0]), &out, &olen, &e) ==
                      API_EINVALID &&
                  strstr(e.msg, bad[i][1]),
              "case %zu: %s", i, e.msg);
    mesh_file g = {"c.stl", MESH_STL, "solid\n", 6};
    CHECK(mesh_request_json(&g, 1, NULL, 0, &out, &olen, &e) == API_EINVALID &&
              !strncmp(e.msg, "c.stl: line ", 12),
          "%s", e.msg);
    free(t);
}

TEST(format_names)
{
    CHECK(mesh_format_of_name("a/B.STL") == MESH_STL && mesh_format_of_name("x.3mf") == MESH_3MF &&
              mesh_format_of_name("x.ply") == MESH_PLY && mesh_format_of_name("x.stl/y") == 0 &&
              mesh_format_of_name("x") == 0,
          "by name");
    CHECK(mesh_format_of_media("model/stl; charset=x") == MESH_STL &&
              mesh_format_of_media("Model/3MF") == MESH_3MF &&
              mesh_format_of_media("model/vnd.off") == MESH_OFF &&
              mesh_format_of_media("model/vnd.ply") == MESH_PLY &&
              mesh_format_of_media("model/obj") == MESH_OBJ &&
              mesh_format_of_media("model/stlx") == 0 && mesh_format_of_media(NULL) == 0,
          "by media type");
    CHECK(render_format_named("stl") && render_format_named("off") && render_format_named("3mf") &&
              render_format_named("glb") &&
              !strcmp(render_format_named("glb")->media, "model/gltf-binary"),
          "rows");
}
