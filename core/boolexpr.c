/* boolexpr.c — see boolexpr.h. */
#include "core/boolexpr.h"

#include <stdlib.h>
#include <string.h>

#include "core/mem.h"
#include "core/util.h"

int bool_expr_push(bool_expr *e, int32_t instr)
{
    if (e->n >= BOOL_MAX_CODE) return -1;
    if (mem_grow(&e->code, &e->cap, e->n + 1, sizeof *e->code)) return -1;
    e->code[e->n++] = instr;
    return 0;
}

int bool_expr_named(const char *name, size_t ninputs, bool_expr *out)
{
    memset(out, 0, sizeof *out);
    if (ninputs == 0 || ninputs > BOOL_MAX_CODE / 2) return -1;
    int32_t op;
    if (!strcmp(name, "union"))
        op = BOOL_OR;
    else if (!strcmp(name, "intersection"))
        op = BOOL_AND;
    else if (!strcmp(name, "xor"))
        op = BOOL_XOR;
    else if (!strcmp(name, "difference"))
        op = BOOL_SUB;
    else
        return -1;
    int rc = bool_expr_push(out, 0);
    if (op == BOOL_SUB) { /* 0 - (1 + 2 + ...) */
        for (size_t i = 1; i < ninputs && !rc; i++) {
            rc = bool_expr_push(out, (int32_t)i);
            if (i > 1 && !rc) rc = bool_expr_push(out, BOOL_OR);
        }
        if (ninputs > 1 && !rc) rc = bool_expr_push(out, BOOL_SUB);
    } else {
        for (size_t i = 1; i < ninputs && !rc; i++) {
            rc = bool_expr_push(out, (int32_t)i);
            if (!rc) rc = bool_expr_push(out, op);
        }
    }
    if (rc || bool_expr_check(out, ninputs)) {
        bool_expr_free(out);
        return -1;
    }
    return 0;
}

int bool_expr_check(bool_expr *e, size_t ninputs)
{
    size_t d = 0, maxd = 0;
    for (size_t i = 0; i < e->n; i++) {
        int32_t c = e->code[i];
        if (c >= 0) {
            if ((size_t)c >= ninputs) return -1;
            if (++d > maxd) maxd = d;
        } else {
            if (c < BOOL_XOR || d < 2) return -1;
            d--;
        }
    }
    if (d != 1) return -1;
    e->depth = maxd;
    return 0;
}

int bool_expr_eval(const bool_expr *e, const uint8_t *member, uint8_t *stack)
{
    size_t d = 0;
    for (size_t i = 0; i < e->n; i++) {
        int32_t c = e->code[i];
        if (c >= 0) {
            stack[d++] = member[c] ? 1 : 0;
            continue;
        }
        uint8_t b = stack[--d], a = stack[d - 1];
        switch (c) {
        case BOOL_OR:
            a = a | b;
            break;
        case BOOL_AND:
            a = a & b;
            break;
        case BOOL_SUB:
            a = a & !b;
            break;
        default:
            a = a ^ b;
            break;
        }
        stack[d - 1] = a;
    }
    return stack[0];
}

void bool_expr_free(bool_expr *e)
{
    free(e->code);
    memset(e, 0, sizeof *e);
}

/* ---- sparse evaluation ----------------------------------------------------------------------- */

void bool_tree_free(bool_tree *t)
{
    free(t->op);
    free(t->parent);
    free(t->arity);
    free(t->depth);
    free(t->left);
    free(t->occ_off);
    free(t->occ);
    free(t->count);
    free(t->lefton);
    free(t->queued);
    free(t->heap);
    memset(t, 0, sizeof *t);
}

static int associative(int32_t op)
{
    return op == BOOL_OR || op == BOOL_AND || op == BOOL_XOR;
}

int bool_tree_build(const bool_expr *e, size_t ninputs, bool_tree *t)
{
    size_t n = e->n, sp = 0, nn = 0;
    uint32_t *stack = malloc((e->depth + 1) * sizeof *stack);
    uint32_t *fwd = malloc((n + 1) * sizeof *fwd); /* a node merged into another: that one */
    memset(t, 0, sizeof *t);
    t->ninputs = ninputs;
    t->op = malloc((n + 1) * sizeof *t->op);
    t->parent = malloc((n + 1) * sizeof *t->parent);
    t->arity = calloc(n + 1, sizeof *t->arity);
    t->depth = calloc(n + 1, sizeof *t->depth);
    t->left = calloc(n + 1, 1);
    t->occ_off = calloc(ninputs + 2, sizeof *t->occ_off);
    t->occ = malloc((n + 1) * sizeof *t->occ);
    t->count = calloc(n + 1, sizeof *t->count);
    t->lefton = calloc(n + 1, 1);
    t->queued = calloc(n + 1, 1);
    t->heap = malloc((n + 1) * sizeof *t->heap);
    if (!stack || !fwd || !t->op || !t->parent || !t->arity || !t->depth || !t->left ||
        !t->occ_off || !t->occ || !t->count || !t->lefton || !t->queued || !t->heap) {
        free(stack);
        free(fwd);
        bool_tree_free(t);
        return -1;
    }
    for (size_t i = 0; i < n; i++) {
        int32_t c = e->code[i];
        uint32_t id = (uint32_t)nn++;
        fwd[id] = id;
        t->op[id] = c;
        t->parent[id] = UINT32_MAX;
        if (c >= 0) {
            stack[sp++] = id;
            continue;
        }
        uint32_t b = stack[--sp], a = stack[--sp], into = id;
        /* a chain of one associative operator becomes one node: grow a's node */
        if (associative(c) && t->op[a] == c) {
            into = a;
            fwd[id] = a;
            nn--; /* id unused */
        } else {
            t->parent[a] = id;
            t->left[a] = c == BOOL_SUB;
            t->arity[id] = 1;
        }
        if (associative(c) && t->op[b] == c) { /* b's children join too */
            fwd[b] = into;
            t->arity[into] += t->arity[b];
        } else {
            t->parent[b] = into;
            t->arity[into]++;
        }
        stack[sp++] = into;
    }
    /* parents through the merges, then depths */
    uint32_t root = sp == 1 ? stack[0] : 0;
    for (size_t v = 0; v < nn; v++)
        if (uf_find(fwd, (uint32_t)v) == v && t->parent[v] != UINT32_MAX)
            t->parent[v] = uf_find(fwd, t->parent[v]);
    t->parent[root] = UINT32_MAX;
    t->nnodes = nn;
    /* depth: walk up to a node whose depth is known, then down again (each node once) */
    for (size_t v = 0; v < nn; v++) {
        uint32_t u = (uint32_t)v, d, w;
        if (uf_find(fwd, u) != u || t->queued[u]) continue;
        while (t->parent[u] != UINT32_MAX && !t->queued[u]) u = t->parent[u];
        d = t->queued[u] ? t->depth[u] : 0;
        t->depth[u] = d;
        t->queued[u] = 1;
        /* the path from v up to u, deepest last: count its length, then fill it in */
        size_t len = 0;
        for (w = (uint32_t)v; w != u; w = t->parent[w]) len++;
        for (w = (uint32_t)v; w != u; w = t->parent[w]) {
            t->depth[w] = d + (uint32_t)len--;
            t->queued[w] = 1;
        }
    }
    memset(t->queued, 0, n + 1);
    /* the leaves of each input */
    for (size_t v = 0; v < nn; v++)
        if (t->op[v] >= 0 && uf_find(fwd, (uint32_t)v) == v) t->occ_off[t->op[v] + 1]++;
    for (size_t i = 0; i < ninputs; i++) t->occ_off[i + 1] += t->occ_off[i];
    for (size_t v = 0; v < nn; v++)
        if (t->op[v] >= 0 && uf_find(fwd, (uint32_t)v) == v)
            t->occ[t->occ_off[t->op[v]]++] = (uint32_t)v;
    for (size_t i = ninputs; i > 0; i--) t->occ_off[i] = t->occ_off[i - 1];
    t->occ_off[0] = 0;
    free(stack);
    free(fwd);
    return 0;
}

/* the heap of touched nodes, deepest first */
static void heap_push(bool_tree *t, size_t *h, uint32_t v)
{
    size_t i = (*h)++;
    while (i > 0) {
        size_t p = (i - 1) / 2;
        if (t->depth[t->heap[p]] >= t->depth[v]) break;
        t->heap[i] = t->heap[p];
        i = p;
    }
    t->heap[i] = v;
}

static uint32_t heap_pop(bool_tree *t, size_t *h)
{
    uint32_t top = t->heap[0], last = t->heap[--*h];
    size_t i = 0, n = *h;
    for (;;) {
        size_t c = 2 * i + 1;
        if (c >= n) break;
        if (c + 1 < n && t->depth[t->heap[c + 1]] > t->depth[t->heap[c]]) c++;
        if (t->depth[t->heap[c]] <= t->depth[last]) break;
        t->heap[i] = t->heap[c];
        i = c;
    }
    if (n) t->heap[i] = last;
    return top;
}

/* A child v found 1: counted at its parent, which is queued. */
static void found_one(bool_tree *t, size_t *h, uint32_t v)
{
    uint32_t p = t->parent[v];
    if (p == UINT32_MAX) return;
    t->count[p]++;
    if (t->left[v]) t->lefton[p] = 1;
    if (!t->queued[p]) {
        t->queued[p] = 1;
        heap_push(t, h, p);
    }
}

int bool_tree_eval(bool_tree *t, const uint32_t *in, size_t k)
{
    size_t h = 0;
    int rootval = 0;
    if (t->nnodes == 0) return 0;
    for (size_t j = 0; j < k; j++) {
        uint32_t i = in[j];
        for (uint32_t o = t->occ_off[i]; o < t->occ_off[i + 1]; o++) {
            uint32_t v = t->occ[o];
            if (t->parent[v] == UINT32_MAX) rootval = 1; /* the program is one input */
            found_one(t, &h, v);
        }
    }
    while (h > 0) {
        uint32_t v = heap_pop(t, &h);
        uint32_t c = t->count[v];
        int val;
        switch (t->op[v]) {
        case BOOL_OR:
            val = c > 0;
            break;
        case BOOL_AND:
            val = c == t->arity[v];
            break;
        case BOOL_XOR:
            val = c & 1;
            break;
        default: /* BOOL_SUB: the left operand and not the right */
            val = t->lefton[v] && c == 1;
            break;
        }
        t->count[v] = 0;
        t->lefton[v] = 0;
        t->queued[v] = 0;
        if (!val) continue;
        if (t->parent[v] == UINT32_MAX)
            rootval = 1;
        else
            found_one(t, &h, v);
    }
    return rootval;
}
