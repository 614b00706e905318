/* meshio.h — meshes in (issue 28, items 1 and 4): STL, PLY and 3MF files read into solids
 * (core/solid.h), next to the OBJ and OFF readers of the core; a mesh file's format from its
 * name or media type; and the "solids" request of a list of mesh files, as the daemon makes it
 * of a mesh body or a multipart/form-data body (api/meshio.c).
 *
 * Formats read:
 *   STL   binary or ASCII.  Binary when the size is 84 + 50 n (n the count at byte 80) and the
 *         text does not parse as ASCII STL, or when the file does not start with "solid";
 *         ASCII when it starts with "solid" (after blanks) and parses (a binary file whose
 *         header starts with "solid" is still read as binary: its size decides).  Vertices are
 *         welded exactly: the same three coordinates (bit for bit, -0 taken as 0) are one
 *         vertex; no tolerance.  Facet normals are ignored (the orientation is the vertex
 *         order).  Several "solid ... endsolid" blocks of an ASCII file are one solid.
 *   PLY   ascii 1.0, binary_little_endian 1.0, binary_big_endian 1.0.  The element "vertex"
 *         gives x, y, z (any scalar type); the element "face" a list property vertex_indices
 *         (or vertex_index) of any count and index types, one polygon per face; every other
 *         element and property is skipped by its declared type.
 *   3MF   a zip (libzip) whose root model part is named by _rels/.rels (the relationship of
 *         type .../3dmodel), else 3D/3dmodel.model; the XML (libxml2's reader, no DTD, no
 *         network) gives objects; every build item is one solid per mesh object it reaches
 *         through components, with the item's and the components' transforms applied
 *         (3MF's row-vector affine maps; a mirroring one reverses the triangles).  A model
 *         without build items gives each mesh object once, as it is.  Units are not converted
 *         (a model in inches gives inches); other parts (production extension's p:path) and
 *         every extension's data are ignored.
 * Limits (MESH_*): bytes a 3MF part inflates to, XML depth, header lines of PLY, counts; a
 * file that passes them is a value, never a crash.  Errors are -1 with a message in err that
 * names where: "triangle 7: vertex 2: coordinate not finite", "line 12: expected \"vertex\"",
 * "3D/3dmodel.model: line 4: vertex 2: y: expected a number"; the caller puts the file name in
 * front ("a.stl: triangle 7: ...").
 *
 * Threads: reentrant; libxml2 is used through its reader only (no global state changed).
 * Ownership: inputs are borrowed; a solid read is the caller's (solid_free()); a parts array
 * is malloc'd (solid_free each, then free()).
 */
#ifndef CELLAR_MESHIO_H
#define CELLAR_MESHIO_H

#include <stddef.h>

#include "api/api.h"
#include "core/solid.h"

#define MESH_MAX_TRIANGLES (1u << 26)    /* triangles (and faces) of one file */
#define MESH_MAX_VERTICES  (1u << 26)    /* vertices of one file */
#define MESH_PLY_HEADER    65536         /* bytes of a PLY header */
#define MESH_PLY_ELEMENTS  64            /* elements of a PLY header, properties of each */
#define MESH_PLY_POLYGON   4096          /* vertices of one PLY face */
#define MESH_3MF_MAX_PART  (256ul << 20) /* bytes a 3MF part inflates to (zip bombs) */
#define MESH_3MF_MAX_RELS  (1ul << 20)   /* bytes of _rels/.rels */
#define MESH_3MF_DEPTH     64            /* XML nesting */
#define MESH_3MF_OBJECTS   65536         /* objects of a model */
#define MESH_3MF_SOLIDS    4096          /* solids (build items times components) of a file */
#define MESH_3MF_NESTING   16            /* components within components */

/* The bytes a 3MF part may inflate to in this process: MESH_3MF_MAX_PART, or less as set (the
 * daemon sets its --max-body: a 3MF body must not make more than a JSON body may hold).  Both
 * thread-safe; set it before the readers run. */
void mesh_set_max_part(size_t bytes);
size_t mesh_max_part(void);

typedef enum mesh_format {
    MESH_NONE = 0,
    MESH_OBJ,
    MESH_OFF,
    MESH_STL,
    MESH_PLY,
    MESH_3MF
} mesh_format;

/* The format of a file by the extension of its name (.obj .off .stl .ply .3mf, any case), or
 * MESH_NONE. */
mesh_format mesh_format_of_name(const char *name);

/* The format a media type names (parameters after ';' ignored, any case), or MESH_NONE:
 *   model/obj                                   OBJ
 *   model/vnd.off, model/x-off                  OFF
 *   model/stl, model/x.stl-binary, model/x.stl-ascii, application/sla,
 *   application/vnd.ms-pki.stl                  STL
 *   model/vnd.ply, model/x-ply, application/ply PLY
 *   model/3mf, application/vnd.ms-3mfdocument   3MF */
mesh_format mesh_format_of_media(const char *media);

/* "obj", "off", "stl", "ply", "3mf" ("?" for MESH_NONE). */
const char *mesh_format_name(mesh_format f);

/* One solid of an STL or PLY file.  Returns 0, or -1 with a message in err (out then empty). */
int mesh_read_stl(const char *data, size_t len, solid *out, char *err, size_t errlen);
int mesh_read_ply(const char *data, size_t len, solid *out, char *err, size_t errlen);

/* The solids of a 3MF file (*nparts >= 0: a model with no mesh gives none).  Returns 0, or -1
 * with a message in err (*parts NULL, *nparts 0). */
int mesh_read_3mf(const char *data, size_t len, solid **parts, size_t *nparts, char *err,
                  size_t errlen);

/* Any format: OBJ as solid_read_obj_parts() (groups as there), OFF, STL, PLY one solid, 3MF
 * its solids.  Returns 0, or -1 with a message in err (*parts NULL, *nparts 0). */
int mesh_read(mesh_format f, const char *data, size_t len, int groups, solid **parts,
              size_t *nparts, char *err, size_t errlen);

/* A mesh file of a request: its name (for messages: "a.stl", "part 2 (\"b\")"), format, bytes. */
typedef struct mesh_file {
    const char *name;
    mesh_format format;
    const char *data;
    size_t len;
} mesh_file;

/* The request {"kind":"solids","solids":[every solid of every file, in order], and the
 * members of request} as JSON text, request[0..rlen) (may be NULL) a JSON object of "op",
 * "options" and "fields" only.  Returns API_OK with *out malloc'd (*outlen bytes, NUL
 * after), or API_EINVALID ("a.stl: triangle 7: ...", "request: unknown key \"x\" ...",
 * "request: not JSON ...", "no solid in the files"), or API_ENOMEM. */
int mesh_request_json(const mesh_file *files, size_t n, const char *request, size_t rlen,
                      char **out, size_t *outlen, api_error *err);

#endif
