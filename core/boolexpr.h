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
    size_t cap;    /* room in code (mem_grow); a bool_expr starts zeroed */
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

/* ---- sparse evaluation (issue "Booleans of many operands") ---------------------------------
 * A cell usually lies in a few of many inputs; its membership is then the sorted list of those
 * inputs, and evaluating the program on a dense row would cost the number of inputs per cell.
 * bool_tree is the program as a tree whose chains of one associative operator (OR, AND, XOR)
 * are merged into one node with many children (a union of 100 000 inputs is one node); a
 * subtree without a member evaluates to 0 under every operator, so a cell's value follows from
 * the ancestors of its members' leaves alone: per cell, time about (members x depth). */
typedef struct bool_tree {
    size_t nnodes, ninputs;
    int32_t *op;       /* per node: >= 0 a leaf (input), else a BOOL_* operator */
    uint32_t *parent;  /* per node; the root's is UINT32_MAX */
    uint32_t *arity;   /* per node: its children */
    uint32_t *depth;   /* per node: edges to the root */
    uint8_t *left;     /* per node: the left operand of its BOOL_SUB parent */
    uint32_t *occ_off; /* ninputs + 1: the leaves of input i are occ[occ_off[i] .. [i+1]) */
    uint32_t *occ;
    /* scratch of one evaluation (bool_tree_eval is not reentrant on one tree: one per thread) */
    uint32_t *count; /* per node: children found 1 */
    uint8_t *lefton; /* per node: its left operand (BOOL_SUB) found 1 */
    uint8_t *queued; /* per node */
    uint32_t *heap;  /* nnodes */
} bool_tree;

/* Builds the tree of a checked program over ninputs inputs; 0, or -1 out of memory. */
int bool_tree_build(const bool_expr *e, size_t ninputs, bool_tree *t);

/* The program's value on a cell whose members are in[0..k) (inputs, any order, each once). */
int bool_tree_eval(bool_tree *t, const uint32_t *in, size_t k);

void bool_tree_free(bool_tree *t);

#endif
