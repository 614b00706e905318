/* boolop.c — the "op" of a request (issue "Boolean chains"): a named variadic operation or an
 * expression tree, compiled to a core bool_expr.
 *
 *   "op": "union" | "intersection" | "difference" | "xor"      (over all inputs)
 *   "op": ["-", 0, ["+", 1, 2]]   operators + & - ^ (union, intersection, difference, xor), each
 *                                 with two operands or more ("-": the first minus the others);
 *                                 an operand is an input index or a nested expression.
 * Errors name the JSON path ("op[2][1]: input 7 out of range (3 inputs)").  Nesting is limited
 * to API_BOOL_MAX_DEPTH levels (jansson's own limit is far above).
 */
#include "api/api_int.h"

#include <stdio.h>
#include <string.h>

#define API_BOOL_MAX_DEPTH 64

/* Pushes the union of layer k's inputs. */
static int push_layer(const api_layers *ly, size_t k, bool_expr *e, api_error *err)
{
    for (uint32_t i = ly->first[k]; i < ly->first[k + 1]; i++)
        if (bool_expr_push(e, (int32_t)i) || (i > ly->first[k] && bool_expr_push(e, BOOL_OR)))
            return api_fail(err, API_ENOMEM, "out of memory (or more than %d codes)",
                            BOOL_MAX_CODE);
    return API_OK;
}

/* The layer named s (the JSON text of each name is compared with s's), or -1. */
static long find_layer(const api_layers *ly, const char *s)
{
    json_t *js = json_string(s);
    char *t = js ? json_dumps(js, JSON_ENCODE_ANY | JSON_COMPACT) : NULL;
    json_decref(js);
    long k = -1;
    for (size_t i = 0; t && i < ly->n && k < 0; i++)
        if (!strcmp(ly->name[i], t)) k = (long)i;
    free(t);
    return k;
}

static int compile(const json_t *t, size_t ninputs, const api_layers *ly, bool_expr *e, char *path,
                   size_t plen, int depth, api_error *err)
{
    if (ly && json_is_string(t)) {
        long k = find_layer(ly, json_string_value(t));
        if (k >= 0) {
            if (ly->first[k] == ly->first[k + 1])
                return api_fail(err, API_EINVALID, "%s: layer %s is empty", path, ly->name[k]);
            return push_layer(ly, (size_t)k, e, err);
        }
        char names[512] = "";
        for (size_t i = 0, n = 0; i < ly->n && n + 1 < sizeof names; i++)
            n += (size_t)snprintf(names + n, sizeof names - n, "%s%s", i ? ", " : "", ly->name[i]);
        return api_fail(err, API_EINVALID, "%s: \"%.100s\" is not a layer (the layers: %s)", path,
                        json_string_value(t), names);
    }
    if (json_is_integer(t)) {
        json_int_t i = json_integer_value(t);
        if (i < 0 || (size_t)i >= ninputs)
            return api_fail(err, API_EINVALID, "%s: input %lld out of range (%zu inputs)", path,
                            (long long)i, ninputs);
        if (bool_expr_push(e, (int32_t)i)) return api_fail(err, API_ENOMEM, "out of memory");
        return API_OK;
    }
    if (!json_is_array(t) || json_array_size(t) < 3)
        return api_fail(err, API_EINVALID, "%s: expected %s or [operator, operand, operand, ...]",
                        path, ly ? "a layer's name, an input index" : "an input index");
    if (depth >= API_BOOL_MAX_DEPTH)
        return api_fail(err, API_EINVALID, "%s: expressions nest deeper than %d levels", path,
                        API_BOOL_MAX_DEPTH);
    const char *s = json_string_value(json_array_get(t, 0));
    int32_t op;
    if (s && !strcmp(s, "+"))
        op = BOOL_OR;
    else if (s && !strcmp(s, "&"))
        op = BOOL_AND;
    else if (s && !strcmp(s, "-"))
        op = BOOL_SUB;
    else if (s && !strcmp(s, "^"))
        op = BOOL_XOR;
    else
        return api_fail(err, API_EINVALID,
                        "%s[0]: expected an operator: \"+\", \"&\", \"-\" or \"^\"", path);
    size_t n = json_array_size(t), len = strlen(path);
    for (size_t i = 1; i < n; i++) {
        snprintf(path + len, plen - len, "[%zu]", i);
        int rc = compile(json_array_get(t, i), ninputs, ly, e, path, plen, depth + 1, err);
        path[len] = 0;
        if (rc) return rc;
        /* a - b - c is a - (b + c): the rest are or-ed, then subtracted once */
        int32_t join = op == BOOL_SUB ? (i >= 3 ? BOOL_OR : 0) : (i >= 2 ? op : 0);
        if (join && bool_expr_push(e, join)) return api_fail(err, API_ENOMEM, "out of memory");
    }
    if (op == BOOL_SUB && bool_expr_push(e, BOOL_SUB))
        return api_fail(err, API_ENOMEM, "out of memory");
    return API_OK;
}

int api_bool_parse(const json_t *op, size_t ninputs, bool_expr *out, api_error *err)
{
    memset(out, 0, sizeof *out);
    if (ninputs == 0) return api_fail(err, API_EINVALID, "op: there are no inputs to combine");
    if (json_is_string(op)) {
        if (bool_expr_named(json_string_value(op), ninputs, out))
            return api_fail(err, API_EINVALID,
                            "op: expected \"union\", \"intersection\", \"difference\", \"xor\" or "
                            "an expression such as [\"-\", 0, [\"+\", 1, 2]]");
        return API_OK;
    }
    char path[4096] = "op";
    int rc = compile(op, ninputs, NULL, out, path, sizeof path, 0, err);
    if (!rc && bool_expr_check(out, ninputs)) rc = api_fail(err, API_EINTERNAL, "op: bad program");
    if (rc) bool_expr_free(out);
    return rc;
}

int api_bool_parse_layers(const json_t *op, size_t ninputs, const api_layers *ly, bool_expr *out,
                          api_error *err)
{
    memset(out, 0, sizeof *out);
    if (ninputs == 0) return api_fail(err, API_EINVALID, "op: there are no inputs to combine");
    int rc = API_OK;
    if (json_is_string(op)) {
        static const char *const names[] = {"union", "intersection", "difference", "xor"};
        static const int32_t ops[] = {BOOL_OR, BOOL_AND, BOOL_SUB, BOOL_XOR};
        const char *s = json_string_value(op);
        int w = -1;
        for (int i = 0; i < 4; i++)
            if (!strcmp(s, names[i])) w = i;
        if (w < 0)
            return api_fail(err, API_EINVALID,
                            "op: expected \"union\", \"intersection\", \"difference\", \"xor\" "
                            "(over the layers) or an expression over the layers' names such as "
                            "[\"&\", %s, %s]",
                            ly->name[0], ly->n > 1 ? ly->name[1] : ly->name[0]);
        /* the layers' unions combined as the named operation combines its inputs: a - b - c is
         * a - (b + c) */
        for (size_t k = 0; k < ly->n && rc == API_OK; k++) {
            if (ly->first[k] == ly->first[k + 1])
                rc = api_fail(err, API_EINVALID, "op: layer %s is empty", ly->name[k]);
            if (rc == API_OK) rc = push_layer(ly, k, out, err);
            int32_t join = ops[w] == BOOL_SUB ? (k >= 2 ? BOOL_OR : 0) : (k >= 1 ? ops[w] : 0);
            if (rc == API_OK && join && bool_expr_push(out, join))
                rc = api_fail(err, API_ENOMEM, "out of memory");
        }
        if (rc == API_OK && ops[w] == BOOL_SUB && ly->n > 1 && bool_expr_push(out, BOOL_SUB))
            rc = api_fail(err, API_ENOMEM, "out of memory");
    } else {
        char path[4096] = "op";
        rc = compile(op, ninputs, ly, out, path, sizeof path, 0, err);
    }
    if (!rc && bool_expr_check(out, ninputs)) rc = api_fail(err, API_EINTERNAL, "op: bad program");
    if (rc) bool_expr_free(out);
    return rc;
}

int api_fill_parse(const json_t *v, int dflt, int *fill, api_error *err)
{
    static const char *const name[] = {"positive", "nonzero", "odd"}; /* by MEMBER_FILL_* */
    const char *f = json_string_value(v);
    for (int k = 0; f && k < 3; k++)
        if (strcmp(f, name[k]) == 0) {
            *fill = k;
            return API_OK;
        }
    int a = dflt == MEMBER_FILL_POSITIVE ? MEMBER_FILL_ODD : MEMBER_FILL_POSITIVE;
    return api_fail(err, API_EINVALID, "options.fill: expected \"%s\", \"nonzero\" or \"%s\"",
                    name[dflt], name[a]);
}
