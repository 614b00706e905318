/* boolexpr.c — see boolexpr.h. */
#include "core/boolexpr.h"

#include <stdlib.h>
#include <string.h>

int bool_expr_push(bool_expr *e, int32_t instr)
{
    if (e->n >= BOOL_MAX_CODE) return -1;
    if ((e->n & (e->n - 1)) == 0) { /* capacity: powers of two */
        size_t cap = e->n ? 2 * e->n : 8;
        int32_t *c = realloc(e->code, cap * sizeof *c);
        if (!c) return -1;
        e->code = c;
    }
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
