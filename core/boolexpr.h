/* boolexpr.h — Boolean expressions over the inputs of an arrangement (issue "Boolean chains").
 *
 * Once the arrangement exists, every Boolean result between its arguments is a chain of cells:
 * a cell is selected when the expression, evaluated on the cell's membership in each input
 * (1: inside), is 1.  An expression is a small postfix program: an operand pushes one input's
 * membership, an operator pops two values and pushes one.  The variadic operations compile to
 * chains of binary ones: union = OR of all, intersection = AND of all, difference = the first
 * AND NOT (OR of the rest), xor = XOR of all (odd membership count).
 *
 * Threads: reentrant, no globals.  Ownership: a bool_expr owns its code; bool_expr_free().
 */
#ifndef CELLAR_BOOLEXPR_H
#define CELLAR_BOOLEXPR_H

#include <stddef.h>
#include <stdint.h>

enum {
    BOOL_OR = -1,  /* "+", union */
    BOOL_AND = -2, /* "&", intersection */
    BOOL_SUB = -3, /* "-", a and not b */
    BOOL_XOR = -4  /* "^", symmetric difference */
};

#define BOOL_MAX_CODE 1000000 /* operands and operators of one expression */

typedef struct bool_expr {
    size_t n;
    int32_t *code; /* >= 0: push input i; < 0: a BOOL_* operator on the two top values */
    size_t depth;  /* stack depth the program needs */
} bool_expr;

/* The program of a named variadic operation ("union", "intersection", "difference", "xor") over
 * inputs 0 .. ninputs-1.  Returns 0, or -1 (unknown name, no input, out of memory). */
int bool_expr_named(const char *name, size_t ninputs, bool_expr *out);

/* Appends one instruction; 0 or -1 (out of memory, or beyond BOOL_MAX_CODE). */
int bool_expr_push(bool_expr *e, int32_t instr);

/* Checks that the program is well formed for ninputs inputs (operands in range, one value left
 * at the end) and sets e->depth; 0 or -1. */
int bool_expr_check(bool_expr *e, size_t ninputs);

/* Evaluates a checked program on one membership row (ninputs bytes, 0/1); stack has e->depth
 * bytes of scratch. */
int bool_expr_eval(const bool_expr *e, const uint8_t *member, uint8_t *stack);

void bool_expr_free(bool_expr *e);

#endif
