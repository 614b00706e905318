/* store_conn.h — the per-thread connection registry of a store backend (store_sqlite.c,
 * store_pg.c), written once: each thread that uses a store has its own backend connection,
 * found through a pthread key; the registry keeps the list of all of them, so that the store's
 * close closes every one, and the key's destructor unlinks and closes a thread's connection
 * when that thread exits.
 *
 * A backend's connection (its struct store_conn) has a store_conn_link as its FIRST member;
 * the registry makes one with the backend's open callback and closes and frees one with its
 * close callback, and touches nothing else of it.
 *
 * Invariants: a connection is in the list from its registration (store_conns_get's make, or
 * store_conns_add) until its thread exits or store_conns_free; the list owns it meanwhile.
 *
 * Threads: store_conns_get is one pthread_getspecific when the calling thread has its
 * connection (no lock on that path); mu guards the list and is held only to link or unlink,
 * never while a backend talks to its database.  store_conns_free must not run while another
 * thread still uses the store or is exiting after having used it (the daemon closes the store
 * after joining its workers and stopping the HTTP server).
 */
#ifndef CELLAR_STORE_CONN_H
#define CELLAR_STORE_CONN_H

#include <pthread.h>
#include <stddef.h>

/* A backend's connection of one thread (each backend defines the struct, first member a
 * store_conn_link). */
typedef struct store_conn store_conn;

typedef struct store_conns store_conns;

typedef struct store_conn_link {
    store_conns *list;                   /* the registry whose list holds this conn */
    struct store_conn_link *prev, *next; /* in list->head; guarded by list->mu */
} store_conn_link;

struct store_conns {
    pthread_key_t key;     /* the calling thread's store_conn */
    pthread_mutex_t mu;    /* guards head */
    store_conn_link *head; /* every registered connection */
    /* a new connection of the calling thread (ctx given to init), NULL with a message */
    store_conn *(*open)(void *ctx, char *err, size_t errlen);
    void (*close)(store_conn *c); /* closes and frees one (NULL: nothing) */
    void *ctx;
    const char *name; /* "NAME: pthread_setspecific failed" */
    int mu_made, key_made;
};

/* Sets up l (zeroed by the caller) with the backend's callbacks: NULL, or the name of the
 * call that failed ("pthread_mutex_init", "pthread_key_create") for the caller's message;
 * either way store_conns_free(l) undoes what was made. */
const char *store_conns_init(store_conns *l, store_conn *(*open)(void *, char *, size_t),
                             void (*close)(store_conn *), void *ctx, const char *name);

/* The calling thread's connection, made (open) and registered on its first call; NULL with a
 * message in err when it cannot be made. */
store_conn *store_conns_make(store_conns *l, char *err, size_t errlen);

static inline store_conn *store_conns_get(store_conns *l, char *err, size_t errlen)
{
    store_conn *c = pthread_getspecific(l->key);
    return c ? c : store_conns_make(l, err, errlen);
}

/* Registers c (made by the caller) as the calling thread's connection: 0, or -1 when the key
 * cannot be set (c then not registered: still the caller's). */
int store_conns_add(store_conns *l, store_conn *c);

/* Closes every registered connection, on whichever thread made it, and frees what init made
 * (see Threads above).  Harmless on a zeroed or partly set up l. */
void store_conns_free(store_conns *l);

#endif
