/* store_conn.c — the per-thread connection registry of the store backends (server/store_conn.h):
 * the pthread key, the list of connections a store owns, the key's destructor that unlinks and
 * closes an exiting thread's connection, and closing them all at the store's close.
 *
 * Threads: see store_conn.h (mu only to link and unlink; the hot path is store_conns_get's
 * pthread_getspecific).  Ownership: the registry owns the connections in its list.
 */
#include "server/store_conn.h"

#include "core/util.h"
#include "server/store.h"

/* Links c at the head of l's list. */
static void store_conns_link(store_conns *l, store_conn *c)
{
    store_conn_link *k = (store_conn_link *)c; /* the first member */
    k->list = l;
    k->prev = NULL;
    pthread_mutex_lock(&l->mu);
    k->next = l->head;
    if (l->head) l->head->prev = k;
    l->head = k;
    pthread_mutex_unlock(&l->mu);
}

/* The pthread key's destructor: a thread that used the store is exiting. */
static void store_conns_release(void *p)
{
    store_conn_link *k = p;
    store_conns *l = k->list;
    pthread_mutex_lock(&l->mu);
    if (k->prev)
        k->prev->next = k->next;
    else if (l->head == k)
        l->head = k->next;
    if (k->next) k->next->prev = k->prev;
    pthread_mutex_unlock(&l->mu);
    l->close(p);
}

const char *store_conns_init(store_conns *l, store_conn *(*open)(void *, char *, size_t),
                             void (*close)(store_conn *), void *ctx, const char *name)
{
    l->open = open;
    l->close = close;
    l->ctx = ctx;
    l->name = name;
    if (pthread_mutex_init(&l->mu, NULL) != 0) return "pthread_mutex_init";
    l->mu_made = 1;
    if (pthread_key_create(&l->key, store_conns_release) != 0) return "pthread_key_create";
    l->key_made = 1;
    return NULL;
}

store_conn *store_conns_make(store_conns *l, char *err, size_t errlen)
{
    store_conn *c = l->open(l->ctx, err, errlen);
    if (!c) return NULL;
    if (store_conns_add(l, c)) {
        util_seterr(err, errlen, STORE_ERR, "%s: pthread_setspecific failed", l->name);
        l->close(c);
        return NULL;
    }
    return c;
}

int store_conns_add(store_conns *l, store_conn *c)
{
    if (pthread_setspecific(l->key, c) != 0) return -1;
    store_conns_link(l, c);
    return 0;
}

void store_conns_free(store_conns *l)
{
    if (l->key_made) { /* first, so that no thread exiting from now on runs the destructor */
        pthread_setspecific(l->key, NULL);
        pthread_key_delete(l->key);
        l->key_made = 0;
    }
    if (!l->mu_made) return;
    pthread_mutex_lock(&l->mu);
    store_conn_link *k = l->head;
    l->head = NULL;
    pthread_mutex_unlock(&l->mu);
    while (k) {
        store_conn_link *next = k->next;
        l->close((store_conn *)k);
        k = next;
    }
    pthread_mutex_destroy(&l->mu);
    l->mu_made = 0;
}
