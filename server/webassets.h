/* webassets.h — the page cellard serves at / and under /assets/: web/ bundled at build time
 * (web/build.mjs) and embedded by scripts/web-embed.sh as a generated C file
 * (build/gen/web.c) holding this table. */
#ifndef CELLAR_WEBASSETS_H
#define CELLAR_WEBASSETS_H

#include <stddef.h>

typedef struct web_asset {
    const char *path;          /* the URL path: "/" or "/assets/NAME-HASH.EXT" */
    const char *type;          /* Content-Type */
    const char *etag;          /* a strong ETag, quoted: the content's SHA-256, 32 hex digits */
    const char *cache;         /* Cache-Control: "no-cache" for /, immutable for the rest */
    const unsigned char *data; /* the bytes, followed by a NUL */
    size_t len;                /* without the NUL */
} web_asset;

extern const web_asset cellar_web_assets[];
extern const size_t cellar_web_assets_n;

#endif
