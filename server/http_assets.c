/* http_assets.c — gzip (Accept-Encoding, one deflate setting for every answer) and the static
 * documents: the page (web/, bundled at build time and embedded as build/gen/web.c), its
 * assets gzipped once at the first request that takes gzip, and the OpenAPI document with the
 * client's prefix as its "servers" URL.
 *
 * Threads: MHD's threads; the gzipped assets are made once under pthread_once and only read
 * after.
 */
#include "server/http_int.h"

#include <pthread.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <strings.h>

#include "server/webassets.h"

extern const unsigned char cellar_openapi[];
extern const size_t cellar_openapi_len;

/* Whether the Accept-Encoding header takes gzip (or any coding, "*") with q > 0. */
int http_accepts_gzip(struct MHD_Connection *mc)
{
    const char *p = MHD_lookup_connection_value(mc, MHD_HEADER_KIND, "Accept-Encoding");
    while (p && *p) {
        while (*p == ' ' || *p == ',' || *p == '\t') p++;
        size_t n = strcspn(p, ",");
        size_t tl = strcspn(p, ";, \t");
        if (tl > n) tl = n;
        int match = (tl == 4 && !strncasecmp(p, "gzip", 4)) || (tl == 1 && *p == '*');
        const char *q = memmem(p, n, "q=", 2);
        if (match && !(q && strtod(q + 2, NULL) <= 0)) return 1;
        p += n;
    }
    return 0;
}

/* Media types worth compressing: every text we send. */
static int compressible(const char *ctype)
{
    return ctype &&
           (!strncmp(ctype, "application/json", 16) ||
            !strncmp(ctype, "application/problem+json", 24) ||
            !strncmp(ctype, "application/geo+json", 20) || !strncmp(ctype, "image/svg+xml", 13) ||
            !strncmp(ctype, "model/obj", 9) || !strncmp(ctype, "application/x-npz", 17) ||
            !strncmp(ctype, "text/", 5) || !strncmp(ctype, "application/javascript", 22));
}

/* Whether an answer of this type and size goes gzipped to a client that takes gzip. */
int http_worth_gzip(const char *ctype, size_t len)
{
    return compressible(ctype) && len >= 1024;
}

/* Starts a gzip stream (deflate with a gzip header) at `level`; 0 on failure. */
int http_gzip_init(z_stream *z, int level)
{
    return deflateInit2(z, level, Z_DEFLATED, 15 + 16, 8, Z_DEFAULT_STRATEGY) == Z_OK;
}

/* gzip of data[0..len) at `level` (1 for answers: results are big, and the CPU is the jobs'),
 * malloc'd; NULL when out of memory. */
char *http_gzip_buf(const char *data, size_t len, int level, size_t *outlen)
{
    z_stream z = {0};
    if (!http_gzip_init(&z, level)) return NULL;
    size_t cap = deflateBound(&z, (uLong)len) + 32;
    char *out = malloc(cap);
    if (!out) {
        deflateEnd(&z);
        return NULL;
    }
    z.next_in = (Bytef *)data;
    z.avail_in = (uInt)len;
    z.next_out = (Bytef *)out;
    z.avail_out = (uInt)cap;
    int rc = deflate(&z, Z_FINISH);
    *outlen = z.total_out;
    deflateEnd(&z);
    if (rc != Z_STREAM_END) {
        free(out);
        return NULL;
    }
    return out;
}

/* The assets gzipped once (level 9), at the first request that takes gzip: each with its own
 * ETag (the asset's with "-gz"), as a different representation must have. */
typedef struct page_gz {
    char *data; /* NULL: not worth it (small or not text), or out of memory */
    size_t len;
    char etag[48];
} page_gz;
static page_gz *page_gzs;
static pthread_once_t page_gz_once = PTHREAD_ONCE_INIT;

static void page_gz_init(void)
{
    page_gzs = calloc(cellar_web_assets_n ? cellar_web_assets_n : 1, sizeof *page_gzs);
    for (size_t i = 0; page_gzs && i < cellar_web_assets_n; i++) {
        const web_asset *a = &cellar_web_assets[i];
        size_t n = strlen(a->etag);
        if (!http_worth_gzip(a->type, a->len) || n < 2 || n + 3 >= sizeof page_gzs->etag) continue;
        page_gz *g = &page_gzs[i];
        g->data = http_gzip_buf((const char *)a->data, a->len, 9, &g->len);
        if (g->data && g->len >= a->len) { /* no gain */
            free(g->data);
            g->data = NULL;
        }
        snprintf(g->etag, sizeof g->etag, "%.*s-gz\"", (int)(n - 1), a->etag);
    }
}

/* The page (web/, bundled at build time and embedded as build/gen/web.c): "/" and its assets
 * under /assets/ (their names carry a hash of their bytes: immutable), each with a strong ETag
 * (If-None-Match answers 304); an unknown asset is a 404 problem. */
enum MHD_Result http_route_page(conn *c)
{
    size_t i = 0;
    if (c->off && !route_path(c)[0]) { /* the base path without its "/": to the page */
        char loc[CONFIG_PREFIX_MAX + 2];
        http_link_to(c, loc, sizeof loc, "/");
        hdr hs[] = {{MHD_HTTP_HEADER_LOCATION, loc}};
        return http_respond(c, 301, NULL, NULL, 0, 1, hs, 1);
    }
    while (i < cellar_web_assets_n && strcmp(cellar_web_assets[i].path, route_path(c))) i++;
    if (i == cellar_web_assets_n) return http_problem(c, 404, "no such asset", NULL, NULL);
    const web_asset *a = &cellar_web_assets[i];
    const page_gz *g = NULL;
    int gzippable = http_worth_gzip(a->type, a->len);
    if (gzippable) {
        pthread_once(&page_gz_once, page_gz_init);
        if (c->gz && page_gzs && page_gzs[i].data) g = &page_gzs[i];
    }
    int html = !strncmp(a->type, "text/html", 9);
    hdr hs[] = {{MHD_HTTP_HEADER_ETAG, g ? g->etag : a->etag},
                {MHD_HTTP_HEADER_CACHE_CONTROL, a->cache},
                {"X-Content-Type-Options", "nosniff"},
                {g ? MHD_HTTP_HEADER_CONTENT_ENCODING : NULL, "gzip"},
                {gzippable ? MHD_HTTP_HEADER_VARY : NULL, "Accept-Encoding"},
                {html ? "Content-Security-Policy" : NULL,
                 "default-src 'self'; img-src 'self' data: blob:; object-src 'none'; "
                 "base-uri 'none'; form-action 'none'; frame-ancestors 'none'"}};
    size_t nh = sizeof hs / sizeof *hs;
    /* If-None-Match: either representation's tag names the same bytes once decoded */
    const char *inm = MHD_lookup_connection_value(c->mc, MHD_HEADER_KIND, "If-None-Match");
    if (inm && (strstr(inm, a->etag) || !strcmp(inm, "*") ||
                (gzippable && page_gzs && page_gzs[i].etag[0] && strstr(inm, page_gzs[i].etag)))) {
        struct MHD_Response *r = MHD_create_response_from_buffer(0, NULL, MHD_RESPMEM_PERSISTENT);
        return http_queue(c, 304, NULL, r, hs, nh);
    }
    const char *data = g ? g->data : (const char *)a->data;
    size_t len = g ? g->len : a->len;
    struct MHD_Response *r =
        MHD_create_response_from_buffer(len, (void *)data, MHD_RESPMEM_PERSISTENT);
    return http_queue(c, 200, a->type, r, hs, nh);
}

/* The OpenAPI document, its "servers" URL the client's prefix ("/" without one). */
enum MHD_Result http_route_openapi(conn *c)
{
    static const char root[] = "\"servers\": [{\"url\": \"/\"";
    char url[CONFIG_PREFIX_MAX + 2];
    http_link_to(c, url, sizeof url, "%s", "");
    const char *doc = (const char *)cellar_openapi;
    const char *at = memmem(doc, cellar_openapi_len, root, sizeof root - 1);
    if (!url[0] || !at) /* the root (or no such line: the document as it is) */
        return http_respond(c, 200, "application/json", (char *)doc, cellar_openapi_len, 1, NULL,
                            0);
    size_t head = (size_t)(at - doc) + sizeof root - 3; /* at its "/" */
    size_t ul = strlen(url), len = cellar_openapi_len - 1 + ul;
    char *b = malloc(len);
    if (!b) return http_problem(c, 503, "out of memory", "5", NULL);
    memcpy(b, doc, head);
    memcpy(b + head, url, ul);
    memcpy(b + head + ul, doc + head + 1, cellar_openapi_len - head - 1);
    return http_respond(c, 200, "application/json", b, len, 0, NULL, 0);
}
